#pragma once
// System: the only public entry point of the SLAM library. Wires the stages of ARCHITECTURE.md
// section 3 — tracking -> local mapping -> loop closing — and owns their threads.
//
// Modes (SystemConfig::mode):
//   kDeterministic: every stage runs inline in the caller's thread, in order: the frame is
//     tracked; a new keyframe is processed completely by local mapping (its BA never aborted)
//     and then by loop closing (global BA inline). Same input and settings give the same
//     trajectory. Used by tests and evaluation.
//   kThreaded: tracking runs in the caller's thread; local mapping and loop closing each run in a
//     worker thread fed through a queue (bounded to local mapping, unbounded from it, so mapping
//     never blocks while loop closing waits for it); global BA runs in the loop closer's
//     background thread. A new keyframe raises the abort flag of a running local BA (ORB-SLAM2's
//     InterruptBA). Loop closing stops mapping through LocalMappingGate. Shutdown: finish()
//     closes the queues, drains them and joins every thread.
// A worker that throws stores the exception; the next process()/finish() call rethrows it after
// shutting the other stages down, and the trajectory so far stays available.
//
// Per frame (DDL-SLAM Algorithm 1): the CNN mask (given, when a SegmentationStage computed it
// ahead, or computed inline); ORB features once, outside the CNN mask and its border; the
// low-cost pose from them (Tracker::low_cost_pose: last-frame matching and motion-only BA, no
// local map; the constant-velocity prediction when that fails); the multi-view geometry check at
// that pose; the features inside the geometry mask and its border dropped; then the rest of
// tracking with the same features.
//
// Thread-safety: process(), finish() and the accessors must be called from one thread; segment()
// may run on one other thread (a SegmentationStage) meanwhile.

#include <atomic>
#include <exception>
#include <memory>
#include <mutex>
#include <optional>
#include <string>
#include <thread>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/bounded_queue.h"
#include "ddl/core/timing.h"
#include "ddl/io/image_output.h"
#include "ddl/io/rgbd_frame.h"
#include "ddl/io/trajectory_io.h"
#include "ddl/loop/loop_closer.h"
#include "ddl/map/map.h"
#include "ddl/map/map_file.h"
#include "ddl/mapping/local_mapper.h"
#include "ddl/pipeline/dense_mapper.h"
#include "ddl/pipeline/depth_time_aligner.h"
#include "ddl/pipeline/dynamic_front_end.h"
#include "ddl/pipeline/local_mapping_gate.h"
#include "ddl/pipeline/map_correction_follower.h"
#include "ddl/pipeline/system_config.h"
#include "ddl/tracking/tracker.h"
#include "ddl/vocabulary/bow_database.h"
#include "ddl/vocabulary/vocabulary.h"

namespace ddl::pipeline {

/// Counters for the run summary.
struct SystemStatistics {
  std::size_t frames = 0;
  std::size_t frames_tracked = 0;  // tracked when processed (a later map reset drops their poses)
  std::size_t poses = 0;           // poses in the camera trajectory at the end
  std::size_t frames_lost = 0;
  std::size_t relocalizations = 0;
  std::size_t relocalizations_in_same_frame = 0;  // of them: the frame whose tracking failed
  std::size_t frames_with_motion_prior = 0;       // tracked with the motion model's prior
  std::size_t keyframes_created = 0;
  std::size_t keyframes_loaded = 0;              // from the map file (load_map)
  std::size_t map_points_loaded = 0;             // ... and its points
  std::size_t keyframe_depth_images_loaded = 0;  // ... and keyframe depth images (geometry check)
  std::size_t depth_images_aligned = 0;  // depth images moved to their colour image's instant
  std::size_t keyframes = 0;             // alive in the map at the end
  std::size_t map_points = 0;            // alive in the map at the end
  std::size_t loops_closed = 0;
  std::size_t map_resets = 0;
  std::size_t geometry_checks_low_cost = 0;   // geometry check at the low-cost tracking pose
  std::size_t geometry_checks_predicted = 0;  // ... at the constant-velocity prediction (fallback)
  std::size_t geometry_checks_implausible = 0;  // ... whose mask the seed-fraction gate dropped
  // ... not run: a loop correction or global-BA merge moved the keyframes meanwhile (threaded)
  std::size_t geometry_checks_skipped = 0;
  // ... without a reference to test against: the reference keyframe culled (threaded), or no
  // reference with a depth image (dynamic.keyframe_depth_cache)
  std::size_t geometry_checks_without_reference = 0;
  // free-space checks not run: a loop correction or global-BA merge moved the keyframes, or the
  // reference keyframe was culled since the previous frame (threaded)
  std::size_t free_space_checks_skipped = 0;
  std::size_t free_space_regions_dropped = 0;  // regions of other sources judged static
  std::size_t segmentations_turned = 0;        // CNN runs on a frame turned upright (accelerometer)
  std::size_t cnn_pictures_dropped = 0;   // CNN mask regions dropped as pictures (picture_veto)
  std::size_t cnn_pictures_unjudged = 0;  // ... kept unjudged: the flood budget was spent
  DenseStats dense;
};

/// What process() reports about one frame.
struct FrameOutcome {
  tracking::TrackingResult tracking;
  DynamicMasks masks;  // empty masks when dynamic removal is off
};

class System {
 public:
  System(const SystemConfig& config, const camera::PinholeCamera& camera,
         std::shared_ptr<const vocabulary::Vocabulary> vocabulary);
  ~System();
  System(const System&) = delete;
  System& operator=(const System&) = delete;

  /// Tracks one frame (frames in timestamp order): runs the dynamic front end (unless disabled)
  /// and tracking, and hands new keyframes on. `cnn`: the frame's CNN mask from segment() when it
  /// was computed ahead (SegmentationStage); std::nullopt = segment inline.
  FrameOutcome process(const io::RgbdFrame& frame, std::optional<CnnMask> cnn = std::nullopt);

  /// Loads a sparse map saved by save_map() (map/map_file.h), before the first process(): the
  /// first frames relocalize in it, and tracking.localization_only tracks against it without
  /// changing it. Its keyframes get their bags of words and enter the keyframe database (for
  /// relocalization and loop detection). Throws ddl::InputError naming the file when it cannot
  /// be read or was built with another camera or vocabulary; ddl::Error when frames were
  /// processed already.
  map::MapFileContents load_map(const std::string& path);
  /// Writes the sparse map (map/map_file.h); after finish() in threaded mode, so that no stage
  /// changes it meanwhile. Throws ddl::OutputError naming the file.
  void save_map(const std::string& path) const;

  /// The CNN mask of one frame (empty when dynamic removal or segmentation is off). It depends
  /// only on the frame. May run on one other thread while process() runs, provided process() is
  /// then always given the masks (the network serves one thread at a time).
  CnnMask segment(const io::RgbdFrame& frame);

  /// Ends the run: drains the queues, joins the workers, waits for a running global BA
  /// (kInterrupted: aborts it instead, so that Ctrl-C does not wait for it). Rethrows a worker's
  /// exception. Idempotent.
  enum class Finish { kComplete, kInterrupted };
  void finish(Finish how = Finish::kComplete);

  io::Trajectory camera_trajectory() const;
  io::Trajectory keyframe_trajectory() const;
  SystemStatistics statistics() const;
  const TimingStats& timings() const { return timings_; }
  std::shared_ptr<const map::Map> map() const { return map_; }
  const DenseMapper& dense_mapper() const { return *dense_; }
  /// The per-frame pictures (save_masks; the dense stage's save_inpainted_dir) that could not be
  /// written, one message per kind (io/image_output.h); empty when all were written.
  std::vector<std::string> frame_output_errors() const;
  const DynamicFrontEnd& dynamic_front_end() const { return *dynamic_; }
  /// See DynamicFrontEnd::set_stored_mask_mapping; before the first process() or segment().
  void set_stored_mask_mapping(std::function<cv::Mat(const cv::Mat&)> mapping) {
    dynamic_->set_stored_mask_mapping(std::move(mapping));
  }
  /// See DynamicFrontEnd::set_source_area; before the first process() or segment().
  void set_source_area(const cv::Mat& area) { dynamic_->set_source_area(area); }
  const SystemConfig& config() const { return config_; }

 private:
  void mapping_worker();
  void loop_worker();
  void handle_keyframe_inline(const map::KeyFramePtr& keyframe);
  /// Records the local mapping of one keyframe: its total and the mapper's stages.
  void record_local_mapping(double total_ms);
  /// Geometry check and dynamic-memory recall at the low-cost pose of `current` (filling
  /// masks.geometry and masks.memory) and removal of the features in their exclusion mask, which
  /// it returns (empty when neither ran).
  /// Before the checks, `frame`'s depth is moved to its colour image's instant (DepthTimeAligner)
  /// with the motion from the previous tracked pose to the low-cost one.
  cv::Mat remove_moving_features(io::RgbdFrame& frame, tracking::Frame& current,
                                 DynamicMasks& masks);
  /// The last tracked pose, if it is in the world frame of `frame_changes`
  /// (Map::frame_change_count): a loop correction or global-BA merge since leaves none.
  std::optional<SE3> previous_pose(std::uint64_t frame_changes) const;
  std::optional<SE3> constant_velocity_pose(std::uint64_t frame_changes) const;
  void rethrow_worker_error();
  void store_error(std::exception_ptr error);
  void shutdown_workers(bool wait_for_global_ba);

  SystemConfig config_;
  camera::PinholeCamera camera_;
  std::shared_ptr<const vocabulary::Vocabulary> vocabulary_;
  std::shared_ptr<vocabulary::BowDatabase> database_;
  std::shared_ptr<map::Map> map_;
  std::unique_ptr<tracking::Tracker> tracker_;
  std::unique_ptr<mapping::LocalMapper> mapper_;
  std::unique_ptr<loop::LoopCloser> loop_closer_;
  std::unique_ptr<DynamicFrontEnd> dynamic_;
  io::ImageOutputLog saved_masks_{"the saved masks (--save-masks)"};
  std::unique_ptr<DenseMapper> dense_;
  // Fallback pose of the geometry check: constant-velocity prediction from the last two tracked
  // frames.
  std::optional<SE3> last_T_c_w_;
  std::optional<SE3> velocity_;     // T_c(k) c(k-1)
  double last_pose_stamp_s_ = 0.0;  // stamp of last_T_c_w_'s frame
  std::unique_ptr<DepthTimeAligner> depth_aligner_;
  std::uint64_t last_pose_frame_changes_ = 0;  // Map::frame_change_count of last_T_c_w_
  map::KeyFramePtr last_reference_;
  // The dynamic memory's world-frame data follows loop corrections and global-BA merges.
  std::unique_ptr<MapCorrectionFollower> memory_anchor_;
  int frames_since_keyframe_ = 1 << 20;   // deterministic mapping-busy emulation
  std::size_t keyframes_before_map_ = 0;  // keyframes created before the map was last reset
  TimingStats timings_;
  SystemStatistics stats_;

  // Threaded mode only.
  std::unique_ptr<BoundedQueue<map::KeyFramePtr>> mapping_queue_;
  std::unique_ptr<BoundedQueue<map::KeyFramePtr>> loop_queue_;
  // Stop handshake of tracking, local mapping and loop closing (LoopCloser::MappingPause).
  LocalMappingGate mapping_gate_;
  std::thread mapping_thread_;
  std::thread loop_thread_;
  std::mutex error_mutex_;
  std::exception_ptr worker_error_;
  std::atomic<bool> failed_{false};
  bool finished_ = false;
  bool map_loaded_ = false;  // load_map()
};

}  // namespace ddl::pipeline
