#pragma once
// Culling of recently created map points (ORB-SLAM2 LocalMapping::MapPointCulling; ORB-SLAM T-RO
// 2015 section VI-B): a new point must be found by tracking in at least min_found_ratio of the
// frames where it was predicted visible, and, once observation_window keyframes have passed since
// its creation, be observed by more than max_observations (stereo observations count twice).
// A point that survives probation_keyframes keyframes leaves the recent list for good.
// Thread-safety: one instance belongs to local mapping; not shared.

#include <deque>

#include "ddl/map/map.h"
#include "ddl/mapping/local_mapper_config.h"

namespace ddl::mapping {

class RecentPoints {
 public:
  explicit RecentPoints(const PointCullingConfig& config) : config_(config) {}

  /// Puts a point on probation (points created by local mapping or by tracking for a keyframe).
  void add(const map::MapPointPtr& point);
  /// Checks every point on probation against the keyframe now being processed; culled points are
  /// set bad and removed from `map`. Returns the number culled.
  int cull(map::KeyFrameId current_keyframe_id, map::Map& map);
  std::size_t size() const { return points_.size(); }
  void clear() { points_.clear(); }

 private:
  PointCullingConfig config_;
  std::deque<map::MapPointPtr> points_;  // in insertion order
};

}  // namespace ddl::mapping
