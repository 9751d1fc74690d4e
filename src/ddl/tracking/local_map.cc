#include "ddl/tracking/local_map.h"

#include <algorithm>
#include <map>

namespace ddl::tracking {

void LocalMap::clear() {
  keyframes_.clear();
  points_.clear();
  projections_.clear();
}

map::KeyFramePtr LocalMap::update(const Frame& frame) {
  map::KeyFramePtr reference;
  collect_keyframes(frame, reference);
  collect_points();
  return reference;
}

void LocalMap::collect_keyframes(const Frame& frame, map::KeyFramePtr& reference) {
  keyframes_.clear();
  keyframe_marks_.next_round();

  // K1: votes of the frame's points for the keyframes observing them, in keyframe id order.
  std::map<map::KeyFrameId, std::pair<map::KeyFramePtr, int>> votes;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const map::MapPointPtr& point = frame.map_point(i);
    if (!point || point->is_bad()) continue;
    for (const map::MapPoint::Observation& obs : point->observations()) {
      auto& entry = votes[obs.keyframe->id()];
      if (!entry.first) entry.first = obs.keyframe;
      ++entry.second;
    }
  }
  int best_votes = 0;
  for (const auto& [id, entry] : votes) {
    if (entry.first->is_bad()) continue;
    if (entry.second > best_votes) {
      best_votes = entry.second;
      reference = entry.first;
    }
    keyframes_.push_back(entry.first);
    keyframe_marks_.mark(id);
  }

  // K2: neighbours of K1 (ORB-SLAM2 adds one covisible, one child and the parent per keyframe).
  const std::size_t max_keyframes = static_cast<std::size_t>(config_.max_local_keyframes);
  const std::size_t k1_count = keyframes_.size();
  auto try_add = [&](const map::KeyFramePtr& kf) {
    if (!kf || kf->is_bad() || !keyframe_marks_.mark(kf->id())) return false;
    keyframes_.push_back(kf);
    return true;
  };
  for (std::size_t k = 0; k < k1_count && keyframes_.size() < max_keyframes; ++k) {
    const map::KeyFramePtr kf = keyframes_[k];
    const auto covisibles =
        kf->best_covisibles(static_cast<std::size_t>(config_.local_covisibles_per_keyframe));
    for (const map::KeyFramePtr& neighbour : covisibles) {
      if (try_add(neighbour)) break;
    }
    for (const map::KeyFramePtr& child : kf->children()) {
      if (try_add(child)) break;
    }
    try_add(kf->parent());
  }
  // No truncation: the K1 keyframes all stay, as in ORB-SLAM2 (the bound only stops the K2
  // expansion). Cutting the id-ordered list to the bound dropped the newest keyframes, the
  // reference's points among them (found by review, 2026-11-26).
}

void LocalMap::collect_points() {
  points_.clear();
  point_marks_.next_round();
  for (const map::KeyFramePtr& kf : keyframes_) {
    for (map::MapPointPtr& point : kf->map_points()) {
      // Most points are seen by several local keyframes: test the (lock-free) mark first.
      if (!point || point_marks_.is_marked(point->id()) || point->is_bad()) continue;
      point_marks_.mark(point->id());
      points_.push_back(std::move(point));
    }
  }
}

int LocalMap::search(Frame& frame, float radius_factor, FrameMatcher& matcher) {
  // Points the frame already holds (and those its pose estimation rejected) are not searched
  // again; the held ones count as visible.
  IdMarks& in_frame = point_marks_;
  in_frame.next_round();
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const map::MapPointPtr& point = frame.map_point(i);
    if (!point) continue;
    if (point->is_bad()) {
      frame.clear_map_point(i);
      continue;
    }
    point->increase_visible();
    in_frame.mark(point->id());
  }
  for (map::MapPointId id : frame.rejected_points()) in_frame.mark(id);

  projections_.clear();
  PointProjection projection;
  for (const map::MapPointPtr& point : points_) {
    if (in_frame.is_marked(point->id())) continue;
    if (project_in_frustum(frame, point, config_.frustum_min_view_cos, projection)) {
      point->increase_visible();
      projections_.push_back(projection);
    }
  }
  if (projections_.empty()) return 0;
  return matcher.match_projections(frame, projections_, radius_factor, config_.local_search_ratio);
}

}  // namespace ddl::tracking
