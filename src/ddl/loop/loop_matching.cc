#include "ddl/loop/loop_matching.h"

#include <limits>
#include <unordered_set>

#include "ddl/features/matcher.h"

namespace ddl::loop {

std::vector<map::MapPointPtr> search_by_bow(const map::KeyFrame& kf1, const map::KeyFrame& kf2,
                                            float ratio, int max_hamming, bool check_orientation) {
  const map::FrameFeatures& f1 = kf1.features();
  const map::FrameFeatures& f2 = kf2.features();
  const vocabulary::FeatureVector& fv1 = kf1.feature_vector();
  const vocabulary::FeatureVector& fv2 = kf2.feature_vector();
  const std::vector<map::MapPointPtr> points1 = kf1.map_points();
  const std::vector<map::MapPointPtr> points2 = kf2.map_points();
  std::vector<map::MapPointPtr> matches(f1.size());
  std::vector<bool> used2(f2.size(), false);
  features::RotationHistogram histogram;

  vocabulary::for_each_shared_node(
      fv1, fv2,
      [&](const std::vector<std::uint32_t>& node1, const std::vector<std::uint32_t>& node2) {
        for (const std::uint32_t i1 : node1) {
          const map::MapPointPtr& p1 = points1[i1];
          if (!p1 || p1->is_bad()) continue;
          features::NearestTwo nearest;
          for (const std::uint32_t i2 : node2) {
            const map::MapPointPtr& p2 = points2[i2];
            if (used2[i2] || !p2 || p2->is_bad()) continue;
            nearest.offer(features::hamming_distance(f1.descriptors, static_cast<int>(i1),
                                                     f2.descriptors, static_cast<int>(i2)),
                          static_cast<int>(i2));
          }
          if (!nearest.found() || nearest.best >= max_hamming ||
              static_cast<float>(nearest.best) >= ratio * static_cast<float>(nearest.second)) {
            continue;
          }
          const auto i2 = static_cast<std::size_t>(nearest.best_index);
          used2[i2] = true;
          matches[i1] = points2[i2];
          if (check_orientation) {
            histogram.add(f1.keypoints[i1].angle, f2.keypoints[i2].angle, static_cast<int>(i1));
          }
        }
      });
  if (check_orientation) {
    for (const int i1 : histogram.inconsistent_ids()) matches[static_cast<std::size_t>(i1)].reset();
  }
  return matches;
}

int search_by_projection(const map::KeyFrame& keyframe, const SE3& T_c_w,
                         std::span<const map::MapPointPtr> points,
                         std::vector<map::MapPointPtr>& matches,
                         const mapping::CameraIntrinsics& camera, double radius_factor,
                         int max_hamming) {
  const map::FrameFeatures& features = keyframe.features();
  const Vec3d center_w = T_c_w.inverse().translation();
  std::unordered_set<const map::MapPoint*> already;
  for (const map::MapPointPtr& p : matches) {
    if (p) already.insert(p.get());
  }
  std::vector<std::size_t> candidates;
  int added = 0;
  for (const map::MapPointPtr& point : points) {
    if (!point || point->is_bad() || already.count(point.get()) != 0) continue;
    const Vec3d p_w = point->position_w();
    const Vec3d p_c = T_c_w * p_w;
    if (p_c.z() <= 0.0) continue;
    const Vec2d uv = mapping::project(camera, p_c);
    if (!mapping::in_image(features, uv)) continue;
    const Vec3d ray = p_w - center_w;
    const double distance = ray.norm();
    if (distance < point->min_distance() || distance > point->max_distance()) continue;
    if (ray.dot(point->normal_w()) < 0.5 * distance) continue;
    const cv::Mat descriptor = point->descriptor();
    if (descriptor.empty()) continue;
    const int level = point->predict_scale(distance, features.pyramid);
    const double radius =
        radius_factor * features.pyramid.scale_factors[static_cast<std::size_t>(level)];
    features.grid.features_in_area(static_cast<float>(uv.x()), static_cast<float>(uv.y()),
                                   static_cast<float>(radius), 0, features::FeatureGrid::kAnyLevel,
                                   features::SearchWindow::kSquare, candidates);
    int best = std::numeric_limits<int>::max();
    long best_index = -1;
    for (const std::size_t idx : candidates) {
      if (matches[idx]) continue;
      const int kp_level = features.keypoints[idx].octave;
      if (kp_level < level - 1 || kp_level > level) continue;
      const int d =
          features::hamming_distance(descriptor.ptr<std::uint8_t>(0),
                                     features.descriptors.ptr<std::uint8_t>(static_cast<int>(idx)));
      if (d < best) {
        best = d;
        best_index = static_cast<long>(idx);
      }
    }
    if (best_index < 0 || best > max_hamming) continue;
    matches[static_cast<std::size_t>(best_index)] = point;
    already.insert(point.get());
    ++added;
  }
  return added;
}

}  // namespace ddl::loop
