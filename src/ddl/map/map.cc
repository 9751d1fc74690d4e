#include "ddl/map/map.h"

namespace ddl::map {

void Map::reserve_ids(KeyFrameId next_keyframe_id, MapPointId next_map_point_id) {
  KeyFrameId kf = next_keyframe_id_.load();
  while (kf < next_keyframe_id && !next_keyframe_id_.compare_exchange_weak(kf, next_keyframe_id)) {
  }
  MapPointId mp = next_map_point_id_.load();
  while (mp < next_map_point_id &&
         !next_map_point_id_.compare_exchange_weak(mp, next_map_point_id)) {
  }
}

bool Map::add_keyframe(const KeyFramePtr& keyframe) {
  std::lock_guard lock(index_mutex_);
  if (keyframe->id() < floor_) return false;
  if (keyframes_.empty()) keyframe->mark_origin();
  keyframes_[keyframe->id()] = keyframe;
  return true;
}

bool Map::add_map_point(const MapPointPtr& point) {
  std::lock_guard lock(index_mutex_);
  if (point->first_keyframe_id() < floor_) return false;
  points_[point->id()] = point;
  return true;
}

void Map::erase_culled_keyframe(const KeyFramePtr& keyframe) {
  const std::vector<MapPointPtr> points = keyframe->map_points();
  std::lock_guard lock(index_mutex_);
  keyframes_.erase(keyframe->id());
  for (const MapPointPtr& point : points) {
    if (point && point->is_bad()) points_.erase(point->id());
  }
}

void Map::erase_map_point(MapPointId id) {
  std::lock_guard lock(index_mutex_);
  points_.erase(id);
}

std::vector<KeyFramePtr> Map::keyframes() const {
  std::vector<KeyFramePtr> all;
  {
    std::lock_guard lock(index_mutex_);
    all.reserve(keyframes_.size());
    for (const auto& [id, kf] : keyframes_) all.push_back(kf);
  }
  std::erase_if(all, [](const KeyFramePtr& kf) { return kf->is_bad(); });
  return all;
}

std::vector<MapPointPtr> Map::map_points() const {
  std::vector<MapPointPtr> all;
  {
    std::lock_guard lock(index_mutex_);
    all.reserve(points_.size());
    for (const auto& [id, p] : points_) all.push_back(p);
  }
  std::erase_if(all, [](const MapPointPtr& p) { return p->is_bad(); });
  return all;
}

KeyFramePtr Map::keyframe(KeyFrameId id) const {
  std::lock_guard lock(index_mutex_);
  auto it = keyframes_.find(id);
  return it == keyframes_.end() ? nullptr : it->second;
}

std::size_t Map::keyframe_count() const {
  std::lock_guard lock(index_mutex_);
  return keyframes_.size();
}

std::size_t Map::map_point_count() const {
  std::lock_guard lock(index_mutex_);
  return points_.size();
}

KeyFramePtr Map::first_keyframe() const {
  std::lock_guard lock(index_mutex_);
  return keyframes_.empty() ? nullptr : keyframes_.begin()->second;
}

void Map::apply_update(const std::function<void()>& f) {
  std::unique_lock lock(update_mutex_);
  f();
}

void Map::apply_frame_change(const std::function<void()>& f) {
  std::unique_lock lock(update_mutex_);
  frame_change_count_.fetch_add(1);
  f();
}

void Map::read_consistent(const std::function<void()>& f) const {
  std::shared_lock lock(update_mutex_);
  f();
}

KeyFrameId Map::clear() {
  std::lock_guard lock(index_mutex_);
  floor_ = next_keyframe_id_.load();
  // Break KeyFrame -> MapPoint ownership so nothing outlives the map.
  for (auto& [id, kf] : keyframes_) {
    for (std::size_t i = 0; i < kf->features().size(); ++i) kf->erase_map_point(i);
  }
  keyframes_.clear();
  points_.clear();
  return floor_;
}

}  // namespace ddl::map
