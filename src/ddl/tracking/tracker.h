#pragma once
// RGB-D tracking (ORB-SLAM2 Tracking for RGB-D, Mur-Artal & Tardos, T-RO 2017 sections III-E and
// IV): per frame, ORB features outside the dynamic mask, an initial pose from the constant-
// velocity motion model (or BoW matching against the reference keyframe, or relocalization when
// lost), refinement against the local map with motion-only BA, and the keyframe decision.
// The first frame with enough features creates the map from its depth.
//
// The stages live in their own files: frame (features), frame_matching (searches), local_map,
// pose_estimation (motion-only BA), keyframe_decision, keyframe_creation, relocalizer,
// trajectory_recorder. The Tracker only sequences them and keeps the state between frames.
//
// Threads: track() is called for every frame, in order, from one thread (the tracking thread).
// camera_trajectory(), state() and frames_tracked() may be called from any thread (but not from
// inside Map::read_consistent / apply_update: camera_trajectory() takes the map's update lock);
// last_frame() and local_map() from the tracking thread only. While tracking a frame the Tracker
// holds the map's shared update lock (Map::read_consistent), so local BA and loop corrections
// are never seen half-applied. Same input => same output (deterministic).

#include <atomic>
#include <memory>
#include <opencv2/core.hpp>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/io/rgbd_frame.h"
#include "ddl/io/trajectory_io.h"
#include "ddl/map/map.h"
#include "ddl/tracking/frame.h"
#include "ddl/tracking/frame_matching.h"
#include "ddl/tracking/local_map.h"
#include "ddl/tracking/motion_model.h"
#include "ddl/tracking/pose_estimation.h"
#include "ddl/tracking/relocalizer.h"
#include "ddl/tracking/tracker_config.h"
#include "ddl/tracking/tracking_types.h"
#include "ddl/tracking/trajectory_recorder.h"
#include "ddl/vocabulary/bow_database.h"
#include "ddl/vocabulary/vocabulary.h"

namespace ddl::tracking {

class Tracker {
 public:
  /// `camera` is the undistorted camera of the frames (io::DatasetReader::camera()). Throws
  /// ddl::ConfigError for an invalid config or camera, ddl::Error for a null map or vocabulary.
  /// `keyframe_database` is filled by local mapping and read here for relocalization; it may be
  /// null (then relocalization is impossible).
  Tracker(const TrackerConfig& config, const camera::PinholeCamera& camera,
          std::shared_ptr<map::Map> map, std::shared_ptr<const vocabulary::Vocabulary> vocabulary,
          std::shared_ptr<vocabulary::BowDatabase> keyframe_database);

  /// Tracks one frame. `dynamic_mask` (CV_8U, non-zero = ignore) may be empty. Throws
  /// ddl::InputError only for images of the wrong type or size; tracking failure is a state.
  TrackingResult track(const io::RgbdFrame& frame, const cv::Mat& dynamic_mask,
                       const MappingStatus& mapping);

  /// T_w_c of every tracked frame so far, from the current keyframe poses.
  io::Trajectory camera_trajectory() const;

  TrackingState state() const { return state_.load(); }
  const TrackerConfig& config() const { return config_; }
  /// The last frame tracked (features, pose, matches); for diagnostics and the dynamic-object
  /// stages. Tracking thread only.
  const Frame& last_frame() const { return last_frame_; }
  /// Local map (keyframes, points) of the last tracked frame (tracking thread only).
  const LocalMap& local_map() const { return local_map_; }
  std::size_t frames_tracked() const { return trajectory_.tracked_frames(); }

 private:
  void track_locked(Frame& frame, const MappingStatus& mapping, TrackingResult& result);
  bool initialize(Frame& frame, TrackingResult& result);
  bool track_reference_keyframe(Frame& frame);
  bool track_motion_model(Frame& frame);
  bool track_local_map(Frame& frame, TrackingTimings& timings);
  bool relocalize(Frame& frame);
  void maybe_create_keyframe(Frame& frame, const MappingStatus& mapping, TrackingResult& result);
  /// Last frame's pose from its reference keyframe (which local BA may have moved), and its
  /// points replaced by fusion swapped for their replacements.
  void refresh_last_frame();
  void reset(TrackingResult& result);

  TrackerConfig config_;
  std::shared_ptr<map::Map> map_;
  std::shared_ptr<const vocabulary::Vocabulary> vocabulary_;
  std::shared_ptr<vocabulary::BowDatabase> database_;

  FrameBuilder builder_;
  FrameMatcher matcher_;
  FramePoseEstimator estimator_;
  LocalMap local_map_;
  Relocalizer relocalizer_;
  MotionModel motion_model_;
  TrajectoryRecorder trajectory_;

  std::atomic<TrackingState> state_{TrackingState::kNotInitialized};
  FrameId next_frame_id_ = 0;
  Frame last_frame_;
  SE3 last_T_c_r_;  // last frame relative to its reference keyframe
  bool last_frame_tracked_ = false;
  map::KeyFramePtr reference_keyframe_;
  FrameId last_keyframe_frame_id_ = 0;
  FrameId last_relocalization_frame_id_ = 0;
  int local_map_inliers_ = 0;
};

}  // namespace ddl::tracking
