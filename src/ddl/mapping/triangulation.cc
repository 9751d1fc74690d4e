#include "ddl/mapping/triangulation.h"

#include <Eigen/SVD>
#include <cmath>

#include "ddl/mapping/keyframe_matching.h"

namespace ddl::mapping {
namespace {

Eigen::Matrix<double, 3, 4> projection_rows(const SE3& T_c_w) {
  Eigen::Matrix<double, 3, 4> P;
  P.leftCols<3>() = T_c_w.rotation();
  P.col(3) = T_c_w.translation();
  return P;
}

}  // namespace

std::optional<Vec3d> triangulate_linear(const SE3& T1_c_w, const SE3& T2_c_w, const Vec2d& xn1,
                                        const Vec2d& xn2) {
  const Eigen::Matrix<double, 3, 4> P1 = projection_rows(T1_c_w);
  const Eigen::Matrix<double, 3, 4> P2 = projection_rows(T2_c_w);
  Eigen::Matrix4d A;
  A.row(0) = xn1.x() * P1.row(2) - P1.row(0);
  A.row(1) = xn1.y() * P1.row(2) - P1.row(1);
  A.row(2) = xn2.x() * P2.row(2) - P2.row(0);
  A.row(3) = xn2.y() * P2.row(2) - P2.row(1);
  const Eigen::JacobiSVD<Eigen::Matrix4d> svd(A, Eigen::ComputeFullV);
  const Vec4d X = svd.matrixV().col(3);
  if (std::abs(X(3)) < 1e-12) return std::nullopt;
  const Vec3d p = X.head<3>() / X(3);
  if (!p.allFinite()) return std::nullopt;
  return p;
}

NewPointsResult create_new_map_points(const map::KeyFramePtr& current, map::Map& map,
                                      const CameraIntrinsics& camera,
                                      const TriangulationConfig& config,
                                      const std::atomic<bool>* abort) {
  NewPointsResult result;
  const std::vector<map::KeyFramePtr> neighbours =
      current->best_covisibles(static_cast<std::size_t>(config.neighbours));
  const map::FrameFeatures& f1 = current->features();
  const SE3 T1_c_w = current->T_c_w();
  const SE3 T1_w_c = T1_c_w.inverse();
  const Vec3d o1 = T1_w_c.translation();
  const double baseline_m = camera.bf / camera.fx;  // virtual stereo baseline
  const double ratio_factor = config.scale_consistency * f1.pyramid.scale_factor;

  for (std::size_t n = 0; n < neighbours.size(); ++n) {
    if (n > 0 && abort != nullptr && abort->load(std::memory_order_acquire)) {
      result.aborted = true;
      break;
    }
    const map::KeyFramePtr& kf2 = neighbours[n];
    const SE3 T2_c_w = kf2->T_c_w();
    const SE3 T2_w_c = T2_c_w.inverse();
    const Vec3d o2 = T2_w_c.translation();
    // RGB-D: a baseline shorter than the virtual one adds nothing to the depth measurements.
    if ((o2 - o1).norm() < baseline_m) continue;
    if (!kf2->has_bow()) continue;

    const map::FrameFeatures& f2 = kf2->features();
    for (const FeaturePair& pair : search_for_triangulation(*current, *kf2, camera, config)) {
      const std::size_t i1 = pair.index1;
      const std::size_t i2 = pair.index2;
      const cv::KeyPoint& kp1 = f1.keypoints[i1];
      const cv::KeyPoint& kp2 = f2.keypoints[i2];
      const bool stereo1 = has_stereo(f1, i1);
      const bool stereo2 = has_stereo(f2, i2);

      const Vec2d xn1((kp1.pt.x - camera.cx) / camera.fx, (kp1.pt.y - camera.cy) / camera.fy);
      const Vec2d xn2((kp2.pt.x - camera.cx) / camera.fx, (kp2.pt.y - camera.cy) / camera.fy);
      const Vec3d ray1 = T1_w_c.rotation() * xn1.homogeneous();
      const Vec3d ray2 = T2_w_c.rotation() * xn2.homogeneous();
      const double cos_rays = ray1.dot(ray2) / (ray1.norm() * ray2.norm());

      // Parallax a depth measurement offers: the angle the virtual baseline subtends.
      double cos_stereo1 = cos_rays + 1.0;
      double cos_stereo2 = cos_rays + 1.0;
      if (stereo1) cos_stereo1 = std::cos(2.0 * std::atan2(baseline_m / 2.0, f1.depth_m[i1]));
      if (stereo2) cos_stereo2 = std::cos(2.0 * std::atan2(baseline_m / 2.0, f2.depth_m[i2]));
      const double cos_stereo = std::min(cos_stereo1, cos_stereo2);

      std::optional<Vec3d> p_w;
      if (cos_rays < cos_stereo && cos_rays > 0.0 &&
          (stereo1 || stereo2 || cos_rays < config.max_parallax_cos)) {
        p_w = triangulate_linear(T1_c_w, T2_c_w, xn1, xn2);
      } else if (stereo1 && cos_stereo1 < cos_stereo2) {
        p_w = unproject_feature_w(f1, i1, camera, T1_c_w);
      } else if (stereo2 && cos_stereo2 < cos_stereo1) {
        p_w = unproject_feature_w(f2, i2, camera, T2_c_w);
      }
      // Equal depths in both keyframes (a tie) drop the match here, as in ORB-SLAM2.
      // Back-projecting the first instead (review of stop 13) made 35% more points on a sideways
      // test move but cost the bench: walking_rpy ATE 0.0033 -> 0.0062 m, static_rpy 0.0024 ->
      // 0.0026 m (out/bench11, docs/RESULTS.md), so ORB-SLAM2's rule stays.
      if (!p_w) continue;

      const Vec3d p_c1 = T1_c_w * *p_w;
      const Vec3d p_c2 = T2_c_w * *p_w;
      if (p_c1.z() <= 0.0 || p_c2.z() <= 0.0) continue;
      if (reprojection_chi2(f1, i1, camera, p_c1) >
          (stereo1 ? config.chi2_stereo : config.chi2_mono)) {
        continue;
      }
      if (reprojection_chi2(f2, i2, camera, p_c2) >
          (stereo2 ? config.chi2_stereo : config.chi2_mono)) {
        continue;
      }

      // Scale consistency: the distance ratio must agree with the keypoints' octave ratio.
      const double dist1 = (*p_w - o1).norm();
      const double dist2 = (*p_w - o2).norm();
      if (dist1 <= 0.0 || dist2 <= 0.0) continue;
      const double ratio_dist = dist2 / dist1;
      const double ratio_octave = f1.pyramid.scale_factors[static_cast<std::size_t>(kp1.octave)] /
                                  f2.pyramid.scale_factors[static_cast<std::size_t>(kp2.octave)];
      if (ratio_dist * ratio_factor < ratio_octave || ratio_dist > ratio_octave * ratio_factor) {
        continue;
      }

      // The slots may have been filled by a point made with an earlier neighbour.
      if (current->map_point(i1) || kf2->map_point(i2)) continue;
      auto point = std::make_shared<map::MapPoint>(map.next_map_point_id(), *p_w, current);
      point->add_observation(current, i1, stereo1);
      point->add_observation(kf2, i2, stereo2);
      current->set_map_point(i1, point);
      kf2->set_map_point(i2, point);
      point->compute_distinctive_descriptor();
      point->update_normal_and_depth();
      map.add_map_point(point);
      result.created.push_back(std::move(point));
    }
  }
  return result;
}

}  // namespace ddl::mapping
