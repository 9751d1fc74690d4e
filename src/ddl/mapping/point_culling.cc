#include "ddl/mapping/point_culling.h"

namespace ddl::mapping {

void RecentPoints::add(const map::MapPointPtr& point) {
  if (point) points_.push_back(point);
}

int RecentPoints::cull(map::KeyFrameId current_keyframe_id, map::Map& map) {
  int culled = 0;
  std::deque<map::MapPointPtr> kept;
  for (map::MapPointPtr& point : points_) {
    if (point->is_bad()) continue;
    const map::KeyFrameId first = point->first_keyframe_id();
    const auto age = current_keyframe_id >= first ? current_keyframe_id - first : 0;
    if (point->found_ratio() < config_.min_found_ratio ||
        (age >= static_cast<map::KeyFrameId>(config_.observation_window) &&
         point->num_observations() <= config_.max_observations)) {
      point->set_bad();
      map.erase_map_point(point->id());
      ++culled;
      continue;
    }
    if (age >= static_cast<map::KeyFrameId>(config_.probation_keyframes)) continue;
    kept.push_back(std::move(point));
  }
  points_.swap(kept);
  return culled;
}

}  // namespace ddl::mapping
