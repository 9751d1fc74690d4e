#include "ddl/mapping/keyframe_culling.h"

namespace ddl::mapping {

bool is_redundant_keyframe(const map::KeyFrame& keyframe, double close_depth_m,
                           const KeyFrameCullingConfig& config) {
  const map::FrameFeatures& features = keyframe.features();
  const std::vector<map::MapPointPtr> points = keyframe.map_points();
  const int needed = config.min_other_observers;
  int close_points = 0;
  int redundant = 0;
  for (std::size_t i = 0; i < points.size(); ++i) {
    const map::MapPointPtr& point = points[i];
    if (!point || point->is_bad()) continue;
    // RGB-D: only close points count; far ones are weakly constrained and may well be unique.
    const float depth = features.depth_m[i];
    if (depth <= 0.0f || depth > close_depth_m) continue;
    ++close_points;
    if (point->num_observations() <= needed) continue;
    const int level = features.keypoints[i].octave;
    int observers = 0;
    for (const map::MapPoint::Observation& obs : point->observations()) {
      if (obs.keyframe->id() == keyframe.id() || obs.keyframe->is_bad()) continue;
      const int other_level = obs.keyframe->features().keypoints[obs.feature_index].octave;
      if (other_level <= level + 1 && ++observers >= needed) break;
    }
    if (observers >= needed) ++redundant;
  }
  return redundant > config.redundant_ratio * close_points;
}

std::vector<map::KeyFrameId> cull_redundant_keyframes(const map::KeyFramePtr& current,
                                                      map::Map& map,
                                                      vocabulary::BowDatabase& database,
                                                      double close_depth_m,
                                                      const KeyFrameCullingConfig& config) {
  std::vector<map::KeyFrameId> culled;
  if (!config.enabled) return culled;
  for (const map::KeyFramePtr& keyframe : current->covisibles()) {
    if (keyframe->is_origin() || keyframe->is_bad()) continue;
    if (!is_redundant_keyframe(*keyframe, close_depth_m, config)) continue;
    if (!keyframe->set_bad()) continue;  // protected by loop closing: culled on release
    map.erase_culled_keyframe(keyframe);
    database.erase(keyframe->id());
    culled.push_back(keyframe->id());
  }
  return culled;
}

}  // namespace ddl::mapping
