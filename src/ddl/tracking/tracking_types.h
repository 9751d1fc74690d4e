#pragma once
// Values exchanged between the Tracker and the pipeline: what local mapping reports about itself
// before a frame is tracked, and the per-frame outcome (ARCHITECTURE.md section 5: per-frame
// outcomes are values).

#include <cstddef>
#include <optional>
#include <string_view>
#include <vector>

#include "ddl/core/se3.h"
#include "ddl/map/keyframe.h"

namespace ddl::tracking {

/// State of local mapping as seen by the keyframe decision (ORB-SLAM2 NeedNewKeyFrame inputs).
struct MappingStatus {
  bool accepts_keyframes = true;     // local mapping is idle (ORB-SLAM2 AcceptKeyFrames)
  std::size_t queued_keyframes = 0;  // keyframes waiting in its queue
  bool stopped = false;  // local mapping is paused (e.g. during a loop correction): no keyframes
};

enum class TrackingState {
  kNotInitialized,  // no map yet (first frames, or after a reset)
  kOk,              // tracked against the map
  kLost,            // tracking failed; the next frames try to relocalize
  kRelocalized,     // tracked by relocalization: after being lost, or in the frame whose tracking
                    // failed (TrackingResult::relocalized_at_once)
};

std::string_view to_string(TrackingState state);

/// How the frame's pose was first estimated before local-map tracking.
enum class TrackingMethod {
  kNone,               // not tracked
  kInitialization,     // the frame created the map
  kMotionModel,        // constant-velocity prediction + projection matching
  kReferenceKeyFrame,  // BoW matching against the reference keyframe
  kRelocalization,     // BoW candidates + PnP RANSAC
};

std::string_view to_string(TrackingMethod method);

/// Wall-clock time of the stages of Tracker::track, milliseconds.
struct TrackingTimings {
  double features_ms = 0.0;          // grayscale, ORB extraction, depth lookup, grid
  double initial_pose_ms = 0.0;      // motion model / reference keyframe / relocalization / init
  double local_map_ms = 0.0;         // local map update, projection search, pose optimisation
  double local_map_update_ms = 0.0;  //   of which: local keyframes and points
  double local_map_search_ms = 0.0;  //   of which: frustum test and projection matching
  double local_map_pose_ms = 0.0;    //   of which: motion-only BA
  double keyframe_ms = 0.0;          // keyframe decision and creation
  double total_ms = 0.0;             // the whole call
};

/// One keypoint of a frame as tracking left it (for display: the viewer).
struct KeypointStatus {
  float u = 0.0f;  // undistorted level-0 pixel
  float v = 0.0f;
  bool matched = false;  // an inlier match of a map point in the final pose, before a new
                         // keyframe added its new points (false on lost and initialising frames)
};

struct TrackingResult {
  std::size_t frame_index = 0;  // io::RgbdFrame::index
  double timestamp_s = 0.0;
  TrackingState state = TrackingState::kNotInitialized;
  TrackingMethod method = TrackingMethod::kNone;
  std::optional<SE3> T_w_c;             // camera pose when tracked (kOk, kRelocalized)
  int num_inliers = 0;                  // inlier map point matches after local-map tracking
  std::size_t num_features = 0;         // keypoints extracted
  map::KeyFramePtr new_keyframe;        // the keyframe created from this frame, or nullptr; the
                                        // pipeline hands it to local mapping
  map::KeyFramePtr reference_keyframe;  // keyframe the pose is stored relative to
  bool map_reset = false;  // tracking was lost with too few keyframes and cleared the map and the
                           // keyframe database: local mapping / loop closing must reset too
  bool motion_prior_used = false;    // tracked, with the motion model's prediction as a prior of
                                     // the pose (tracking.motion_prior; motion-model tracking only)
  bool relocalized_at_once = false;  // kRelocalized in the frame whose tracking failed
                                     // (tracking.relocalization.same_frame): it may have jumped
                                     // from the last frame, and a pose predicted from that is wrong
  TrackingTimings timings;
  std::vector<KeypointStatus> keypoints;  // every keypoint tracking used (outside the dynamic
                                          // masks), in the frame's order

  bool tracked() const {
    return state == TrackingState::kOk || state == TrackingState::kRelocalized;
  }
};

}  // namespace ddl::tracking
