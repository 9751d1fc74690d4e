#include "ddl/mapping/keyframe_matching.h"

#include <algorithm>
#include <limits>

#include "ddl/features/matcher.h"

namespace ddl::mapping {
namespace {

/// Fundamental matrix with x1^T F12 x2 = 0 for pixels x1 of keyframe 1 and x2 of keyframe 2.
Mat3d fundamental_12(const SE3& T1_c_w, const SE3& T2_c_w, const CameraIntrinsics& camera) {
  const SE3 T_1_2 = T1_c_w * T2_c_w.inverse();
  Mat3d K_inv;
  K_inv << 1.0 / camera.fx, 0.0, -camera.cx / camera.fx, 0.0, 1.0 / camera.fy,
      -camera.cy / camera.fy, 0.0, 0.0, 1.0;
  return K_inv.transpose() * hat(T_1_2.translation()) * T_1_2.rotation() * K_inv;
}

/// ORB-SLAM2 CheckDistEpipolarLine: squared distance of kp2 to the epipolar line of kp1, against
/// chi2 (1 dof) times the variance of kp2's level.
bool near_epipolar_line(const cv::KeyPoint& kp1, const cv::KeyPoint& kp2, const Mat3d& F12,
                        double sigma2, double chi2) {
  const double a = kp1.pt.x * F12(0, 0) + kp1.pt.y * F12(1, 0) + F12(2, 0);
  const double b = kp1.pt.x * F12(0, 1) + kp1.pt.y * F12(1, 1) + F12(2, 1);
  const double c = kp1.pt.x * F12(0, 2) + kp1.pt.y * F12(1, 2) + F12(2, 2);
  const double num = a * kp2.pt.x + b * kp2.pt.y + c;
  const double den = a * a + b * b;
  if (den == 0.0) return false;
  return num * num / den < chi2 * sigma2;
}

}  // namespace

std::vector<FeaturePair> search_for_triangulation(const map::KeyFrame& kf1,
                                                  const map::KeyFrame& kf2,
                                                  const CameraIntrinsics& camera,
                                                  const TriangulationConfig& config) {
  const map::FrameFeatures& f1 = kf1.features();
  const map::FrameFeatures& f2 = kf2.features();
  const vocabulary::FeatureVector& fv1 = kf1.feature_vector();
  const vocabulary::FeatureVector& fv2 = kf2.feature_vector();
  const SE3 T1_c_w = kf1.T_c_w();
  const SE3 T2_c_w = kf2.T_c_w();
  const Mat3d F12 = fundamental_12(T1_c_w, T2_c_w, camera);

  // Epipole: the centre of camera 1 seen from camera 2.
  const Vec3d c1_in_2 = T2_c_w * T1_c_w.inverse().translation();
  const bool epipole_valid = c1_in_2.z() > 0.0;
  const Vec2d epipole = epipole_valid ? project(camera, c1_in_2) : Vec2d::Zero();

  const std::vector<map::MapPointPtr> points1 = kf1.map_points();
  const std::vector<map::MapPointPtr> points2 = kf2.map_points();
  std::vector<bool> used2(f2.size(), false);
  std::vector<FeaturePair> pairs;
  features::RotationHistogram histogram;

  vocabulary::for_each_shared_node(
      fv1, fv2,
      [&](const std::vector<std::uint32_t>& node1, const std::vector<std::uint32_t>& node2) {
        for (const std::uint32_t i1 : node1) {
          if (points1[i1]) continue;
          const bool stereo1 = has_stereo(f1, i1);
          const cv::KeyPoint& kp1 = f1.keypoints[i1];
          int best_distance = config.max_hamming + 1;
          long best_i2 = -1;
          for (const std::uint32_t i2 : node2) {
            if (used2[i2] || points2[i2]) continue;
            const int distance = features::hamming_distance(f1.descriptors, static_cast<int>(i1),
                                                            f2.descriptors, static_cast<int>(i2));
            if (distance >= best_distance) continue;
            const cv::KeyPoint& kp2 = f2.keypoints[i2];
            const auto level2 = static_cast<std::size_t>(kp2.octave);
            if (!stereo1 && !has_stereo(f2, i2) && epipole_valid) {
              // Without depth on either side a match next to the epipole has no parallax.
              const double dx = epipole.x() - kp2.pt.x;
              const double dy = epipole.y() - kp2.pt.y;
              const double min_px = config.epipole_min_px;
              if (dx * dx + dy * dy < min_px * min_px * f2.pyramid.scale_factors[level2]) continue;
            }
            if (!near_epipolar_line(kp1, kp2, F12, f2.pyramid.level_sigma2[level2],
                                    config.epipolar_chi2)) {
              continue;
            }
            best_distance = distance;
            best_i2 = i2;
          }
          if (best_i2 < 0) continue;
          used2[static_cast<std::size_t>(best_i2)] = true;
          if (config.check_orientation) {
            histogram.add(kp1.angle, f2.keypoints[static_cast<std::size_t>(best_i2)].angle,
                          static_cast<int>(pairs.size()));
          }
          pairs.push_back({i1, static_cast<std::size_t>(best_i2)});
        }
      });

  if (config.check_orientation) {
    std::vector<bool> keep(pairs.size(), false);
    for (const int id : histogram.consistent_ids()) keep[static_cast<std::size_t>(id)] = true;
    std::vector<FeaturePair> kept;
    for (std::size_t k = 0; k < pairs.size(); ++k) {
      if (keep[k]) kept.push_back(pairs[k]);
    }
    pairs.swap(kept);
  }
  std::sort(pairs.begin(), pairs.end(),
            [](const FeaturePair& a, const FeaturePair& b) { return a.index1 < b.index1; });
  return pairs;
}

int fuse(const map::KeyFramePtr& keyframe, const SE3& T_c_w,
         std::span<const map::MapPointPtr> points, const CameraIntrinsics& camera,
         const FuseParams& params, map::Map& map) {
  const map::FrameFeatures& features = keyframe->features();
  const Vec3d center_w = T_c_w.inverse().translation();
  const map::KeyFrameId kf_id = keyframe->id();
  std::vector<std::size_t> candidates;
  int fused = 0;

  for (const map::MapPointPtr& point : points) {
    if (!point || point->is_bad() || point->is_in(kf_id)) continue;
    const Vec3d p_w = point->position_w();
    const Vec3d p_c = T_c_w * p_w;
    if (p_c.z() <= 0.0) continue;
    const Vec2d uv = project(camera, p_c);
    if (!in_image(features, uv)) continue;

    const Vec3d ray = p_w - center_w;
    const double distance = ray.norm();
    if (distance < point->min_distance() || distance > point->max_distance()) continue;
    if (ray.dot(point->normal_w()) < params.min_view_cos * distance) continue;

    const cv::Mat descriptor = point->descriptor();
    if (descriptor.empty()) continue;
    const int level = point->predict_scale(distance, features.pyramid);
    const double radius =
        params.radius_factor * features.pyramid.scale_factors[static_cast<std::size_t>(level)];
    features.grid.features_in_area(static_cast<float>(uv.x()), static_cast<float>(uv.y()),
                                   static_cast<float>(radius), 0, features::FeatureGrid::kAnyLevel,
                                   features::SearchWindow::kSquare, candidates);

    int best_distance = std::numeric_limits<int>::max();
    long best_index = -1;
    for (const std::size_t idx : candidates) {
      const int kp_level = features.keypoints[idx].octave;
      if (kp_level < level - 1 || kp_level > level) continue;
      if (params.check_reprojection) {
        const double chi2 = reprojection_chi2(features, idx, camera, p_c);
        if (chi2 > (has_stereo(features, idx) ? params.chi2_stereo : params.chi2_mono)) continue;
      }
      const int d =
          features::hamming_distance(descriptor.ptr<std::uint8_t>(0),
                                     features.descriptors.ptr<std::uint8_t>(static_cast<int>(idx)));
      if (d < best_distance) {
        best_distance = d;
        best_index = static_cast<long>(idx);
      }
    }
    if (best_index < 0 || best_distance > params.max_hamming) continue;
    const auto idx = static_cast<std::size_t>(best_index);

    const map::MapPointPtr existing = keyframe->map_point(idx);
    if (existing && !existing->is_bad()) {
      if (existing == point) continue;
      if (params.conflict == FuseConflict::kKeepMostObserved &&
          existing->num_observations() > point->num_observations()) {
        point->replace_with(existing);
        map.erase_map_point(point->id());
      } else {
        existing->replace_with(point);
        map.erase_map_point(existing->id());
      }
    } else {
      point->add_observation(keyframe, idx, has_stereo(features, idx));
      keyframe->set_map_point(idx, point);
    }
    ++fused;
  }
  return fused;
}

}  // namespace ddl::mapping
