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
// Per frame, DDL-SLAM Algorithm 1 needs a pose before tracking is complete (the multi-view
// geometry check runs at it), so tracking is split into steps called in this order:
//   1. prepare_frame(): ORB features once, outside the CNN exclusion mask;
//   2. low_cost_pose() (optional): the initial-pose step of tracking alone (motion model against
//      the last frame, else BoW matching against the reference keyframe, each with motion-only
//      BA; no local map);
//   3. exclude_features() (optional): features on content found moving are dropped and the
//      low-cost pose is refined without them;
//   4. track(): the rest of tracking with the same Frame (initial pose unless step 2 did it,
//      local map, keyframe decision).
// track(io::RgbdFrame, mask, ...) does steps 1 and 4 in one call.
//
// Threads: the steps are called for every frame, in order, from one thread (the tracking thread).
// camera_trajectory(), state() and frames_tracked() may be called from any thread (but not from
// inside Map::read_consistent / apply_update: camera_trajectory() takes the map's update lock);
// last_frame() and local_map() from the tracking thread only. While tracking a frame the Tracker
// holds the map's shared update lock (Map::read_consistent), so local BA and loop corrections
// are never seen half-applied. Same input => same output (deterministic).

#include <atomic>
#include <memory>
#include <opencv2/core.hpp>
#include <optional>

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

  /// Step 1: the tracking frame of `frame` with ORB features outside `dynamic_mask` (CV_8U,
  /// non-zero = ignore; may be empty). Throws ddl::InputError for images of the wrong type or
  /// size.
  Frame prepare_frame(const io::RgbdFrame& frame, const cv::Mat& dynamic_mask);

  /// Step 2: the low-cost pose T_c_w of a prepared frame. The matches it makes stay in `frame`
  /// and track() continues from them (nothing is computed twice). std::nullopt before the map
  /// exists, while lost (relocalization is not low-cost) or when the pose cannot be estimated;
  /// track() then does the work itself.
  std::optional<SE3> low_cost_pose(Frame& frame);

  /// Step 3: drops the features of `frame` at non-zero pixels of `mask` (CV_8UC1; empty = none);
  /// when some of them carried matches of the low-cost pose, that pose is re-estimated from the
  /// remaining matches. Returns the number of features dropped.
  std::size_t exclude_features(Frame& frame, const cv::Mat& mask);

  /// Step 4: tracks the prepared frame (consumed: it becomes last_frame()). Tracking failure is
  /// a state, not an exception.
  TrackingResult track(Frame frame, const MappingStatus& mapping);

  /// Steps 1 and 4: tracks one frame with features outside `dynamic_mask`.
  TrackingResult track(const io::RgbdFrame& frame, const cv::Mat& dynamic_mask,
                       const MappingStatus& mapping);

  /// Before the first frame, with a map loaded into the tracker's map (map::load_map_file) and
  /// its keyframes in the keyframe database: tracking starts lost, so the first frames
  /// relocalize in that map instead of starting a new one, and being lost never resets it.
  void start_in_loaded_map();

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
  /// Frames whose low-cost pose track() discarded and estimated again because loop closing
  /// moved the world frame in between (threaded mode).
  std::size_t low_cost_poses_redone() const { return low_cost_poses_redone_; }

 private:
  /// What steps 1-3 found out about the frame being prepared (valid for frame_id only).
  struct PreparedFrame {
    FrameId frame_id = 0;
    std::size_t frame_index = 0;  // io::RgbdFrame::index
    double features_ms = 0.0;
    bool initial_pose_done = false;  // low_cost_pose() ran the initial-pose step
    bool initial_pose_ok = false;
    TrackingMethod method = TrackingMethod::kNone;
    double initial_pose_ms = 0.0;
    std::uint64_t frame_changes = 0;  // Map::frame_change_count() at the initial pose
  };

  void track_locked(Frame& frame, const MappingStatus& mapping, TrackingResult& result);
  /// Initial pose of a frame while tracking is ok: motion model, else reference keyframe.
  bool estimate_initial_pose(Frame& frame, TrackingMethod& method);
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
  /// Motion-only BA of the frame, with the motion model's prior while the frame has one.
  int optimize_pose(Frame& frame);

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
  std::optional<optimization::PosePrior> motion_prior_;  // of the frame being tracked
  TrajectoryRecorder trajectory_;

  std::atomic<TrackingState> state_{TrackingState::kNotInitialized};
  FrameId next_frame_id_ = 0;
  PreparedFrame prepared_;
  std::size_t low_cost_poses_redone_ = 0;
  Frame last_frame_;
  SE3 last_T_c_r_;  // last frame relative to its reference keyframe
  bool last_frame_tracked_ = false;
  map::KeyFramePtr reference_keyframe_;
  FrameId last_keyframe_frame_id_ = 0;
  FrameId last_relocalization_frame_id_ = 0;
  int local_map_inliers_ = 0;
  bool map_loaded_ = false;  // start_in_loaded_map(): never reset the map
};

}  // namespace ddl::tracking
