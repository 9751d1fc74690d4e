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
  int tracked = 0;      // close features matched to a map point (not outliers)
  int non_tracked = 0;  // close features without a map point (candidates for new points)
};

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

/// The decision; true = create a keyframe from this frame now.
bool need_new_keyframe(const KeyFrameConfig& config, const KeyFrameContext& context);

}  // namespace ddl::tracking
