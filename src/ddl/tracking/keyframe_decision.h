#pragma once
// Keyframe decision of ORB-SLAM2 for RGB-D (Tracking::NeedNewKeyFrame; T-RO 2017 section III-E
// and the RGB-D "close points" criterion of section IV): insert when enough frames passed or
// mapping is idle, and tracking got weak relative to the reference keyframe or too few close
// points are tracked while many close points could be added.

#include <cstddef>
#include <cstdint>

#include "ddl/tracking/frame.h"
#include "ddl/tracking/tracker_config.h"
#include "ddl/tracking/tracking_types.h"

namespace ddl::tracking {

/// Tracked / untracked features with close depth in a frame.
struct CloseCounts {
  int tracked = 0;              // close features matched to a map point (not outliers)
  int non_tracked = 0;          // close features without a map point (candidates for new points)
  int tracked_established = 0;  // tracked ones whose point >= 2 keyframes observe (not only
                                // created from depth by the last one)
};

/// Counts the close features of a tracked frame. "Established" counts keyframes, not the
/// weighted observations of min_observations_for(): with <= 2 keyframes in the map that asks for
/// 2, which a point created from depth by a single keyframe already has.
CloseCounts count_close_points(const Frame& frame);

/// Everything the decision depends on, gathered by the Tracker.
struct KeyFrameContext {
  FrameId frame_id = 0;
  FrameId last_keyframe_frame_id = 0;  // frame id the last keyframe was made from
  FrameId last_relocalization_frame_id = 0;
  std::size_t keyframes_in_map = 0;
  int reference_tracked_points = 0;  // reference keyframe points with >= min_observations_for
                                     // (keyframes_in_map) observations
  int inliers = 0;                   // local-map inliers of the frame
  CloseCounts close;
  MappingStatus mapping;
};

/// ORB-SLAM2: points of the reference keyframe count when observed at least 3 times (2 while the
/// map has <= 2 keyframes).
int min_observations_for(std::size_t keyframes_in_map);

/// The decision; true = create a keyframe from this frame now. With
/// `config.close_needs_two_keyframes` the close-point criterion counts `close.tracked_established`
/// instead of `close.tracked`: a keyframe creates points from depth for nearly all its close
/// features, and when the camera keeps exploring, the frames after it track mostly those fresh
/// points, so ORB-SLAM2's count stays high until almost nothing links the frame to the keyframes
/// before (and the reference count of the inlier-ratio test, points of >= 2 keyframes, is about
/// that small link, so that test does not fire either): keyframes become sparse and each is held
/// to its predecessor by about `tracked_close_max` points.
bool need_new_keyframe(const KeyFrameConfig& config, const KeyFrameContext& context);

}  // namespace ddl::tracking
