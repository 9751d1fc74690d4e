#include "ddl/tracking/keyframe_creation.h"

#include <algorithm>
#include <utility>
#include <vector>

namespace ddl::tracking {
namespace {

map::KeyFramePtr make_keyframe(Frame& frame, map::Map& map,
                               const vocabulary::Vocabulary& vocabulary, int bow_levels_up) {
  frame.compute_bow(vocabulary, bow_levels_up);
  auto keyframe = std::make_shared<map::KeyFrame>(map.next_keyframe_id(), frame.timestamp_s(),
                                                  frame.features_ptr(), frame.T_c_w());
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const map::MapPointPtr& point = frame.map_point(i);
    if (point && !point->is_bad()) keyframe->set_map_point(i, point);
  }
  return keyframe;
}

/// A map point at keypoint i's back-projected depth, observed by `keyframe`.
void add_point_from_depth(Frame& frame, std::size_t i, const map::KeyFramePtr& keyframe,
                          map::Map& map) {
  auto point =
      std::make_shared<map::MapPoint>(map.next_map_point_id(), frame.unproject_w(i), keyframe);
  point->add_observation(keyframe, i, /*stereo=*/true);
  keyframe->set_map_point(i, point);
  point->compute_distinctive_descriptor();
  point->update_normal_and_depth();
  map.add_map_point(point);
  frame.set_map_point(i, std::move(point));
  frame.set_outlier(i, false);
}

}  // namespace

map::KeyFramePtr create_initial_keyframe(Frame& frame, map::Map& map,
                                         const vocabulary::Vocabulary& vocabulary,
                                         int bow_levels_up) {
  frame.clear_map_points();
  map::KeyFramePtr keyframe = make_keyframe(frame, map, vocabulary, bow_levels_up);
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.has_depth(i)) add_point_from_depth(frame, i, keyframe, map);
  }
  map.add_keyframe(keyframe);
  frame.set_reference_keyframe(keyframe);
  return keyframe;
}

map::KeyFramePtr create_keyframe(Frame& frame, map::Map& map, const KeyFrameConfig& config,
                                 const vocabulary::Vocabulary& vocabulary, int bow_levels_up,
                                 int* new_points) {
  map::KeyFramePtr keyframe = make_keyframe(frame, map, vocabulary, bow_levels_up);

  std::vector<std::pair<float, std::size_t>> by_depth;
  by_depth.reserve(frame.size());
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.has_depth(i)) by_depth.emplace_back(frame.features().depth_m[i], i);
  }
  std::sort(by_depth.begin(), by_depth.end());

  const double close_depth_m = frame.geometry().close_depth_m;
  int visited = 0;
  int created = 0;
  for (const auto& [depth_m, i] : by_depth) {
    const map::MapPointPtr& existing = frame.map_point(i);
    if (!existing || existing->num_observations() < 1) {
      if (existing) keyframe->erase_map_point(i);
      add_point_from_depth(frame, i, keyframe, map);
      ++created;
    }
    ++visited;
    if (depth_m > close_depth_m && visited > config.min_new_close_points) break;
  }
  map.add_keyframe(keyframe);
  frame.set_reference_keyframe(keyframe);
  if (new_points) *new_points = created;
  return keyframe;
}

}  // namespace ddl::tracking
