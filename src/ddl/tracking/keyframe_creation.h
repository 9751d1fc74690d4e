#pragma once
// Creating keyframes from tracked frames, with new map points from measured depth (ORB-SLAM2
// Tracking::StereoInitialization and CreateNewKeyFrame for RGB-D, T-RO 2017 section IV).
//
// The keyframe shares the frame's features, takes the frame's pose and matched points, is added
// to the map, and gets its BoW vector here (tracking computes it before the features become
// shared and const). New points are observed by the keyframe, carry their descriptor, normal and
// distance range, and are added to the map; the existing matched points get their observation of
// the keyframe from local mapping (ORB-SLAM2 ProcessNewKeyFrame), not here.
// Called by the tracking thread.

#include "ddl/map/keyframe.h"
#include "ddl/map/map.h"
#include "ddl/tracking/frame.h"
#include "ddl/tracking/tracker_config.h"
#include "ddl/vocabulary/vocabulary.h"

namespace ddl::tracking {

/// The first keyframe of a map: a map point for every keypoint with depth. The frame's pose must
/// be set (normally the identity: the first camera defines the world frame).
map::KeyFramePtr create_initial_keyframe(Frame& frame, map::Map& map,
                                         const vocabulary::Vocabulary& vocabulary,
                                         int bow_levels_up);

/// A new keyframe from a tracked frame. Keypoints with depth are visited nearest first; those
/// without a map point (or whose point has no observation) get a new point, until the depth
/// passes the close threshold once at least config.min_new_close_points were visited.
/// Returns the keyframe; `new_points` (optional) receives the number of points created.
map::KeyFramePtr create_keyframe(Frame& frame, map::Map& map, const KeyFrameConfig& config,
                                 const vocabulary::Vocabulary& vocabulary, int bow_levels_up,
                                 int* new_points = nullptr);

}  // namespace ddl::tracking
