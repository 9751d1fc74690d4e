#pragma once
// Redundant keyframe culling (ORB-SLAM2 LocalMapping::KeyFrameCulling; ORB-SLAM T-RO 2015 section
// VI-E): a keyframe whose close map points (depth below ThDepth) are, for more than
// redundant_ratio of them, observed by at least min_other_observers other keyframes at the same or
// a finer scale adds nothing and is removed, which keeps the map compact in places the camera
// keeps revisiting. The first keyframe is never culled; keyframes protected by loop closing are
// culled when it releases them (KeyFrame::set_not_erase).
// Thread-safety: any thread; local mapping runs it after local BA.

#include <vector>

#include "ddl/map/keyframe.h"
#include "ddl/map/map.h"
#include "ddl/mapping/local_mapper_config.h"
#include "ddl/vocabulary/bow_database.h"

namespace ddl::mapping {

/// Whether `keyframe` is redundant by the rule above; close_depth_m is ThDepth in metres.
bool is_redundant_keyframe(const map::KeyFrame& keyframe, double close_depth_m,
                           const KeyFrameCullingConfig& config);

/// Checks the covisible keyframes of `current` (strongest first) and removes the redundant ones
/// from the map and the database. Returns the ids of the keyframes removed.
std::vector<map::KeyFrameId> cull_redundant_keyframes(const map::KeyFramePtr& current,
                                                      map::Map& map,
                                                      vocabulary::BowDatabase& database,
                                                      double close_depth_m,
                                                      const KeyFrameCullingConfig& config);

}  // namespace ddl::mapping
