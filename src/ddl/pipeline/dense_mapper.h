#pragma once
// The back end of DDL-SLAM section III-E, after tracking: every new keyframe is repaired by
// background inpainting from the previous (already repaired) keyframes and integrated into the
// OctoMap. It runs in its own thread behind a bounded queue, so neither stage stalls tracking. In
// threaded mode the thread reads the keyframe poses when it gets to them; in deterministic mode
// (deterministic_thread) each step reads the poses and the map's big-change index that submit()
// took for it, so the outputs are those of the inline stage, whatever the thread's timing. When
// loop closing or global BA moves keyframes (Map::big_change_index), the octree is rebuilt from the
// stored repaired keyframes at their corrected poses.
//
// Thread-safety: submit(), finish() and the accessors from one thread (the pipeline's).

#include <atomic>
#include <deque>
#include <exception>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <thread>
#include <unordered_map>
#include <variant>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/bounded_queue.h"
#include "ddl/core/timing.h"
#include "ddl/inpainting/background_inpainter.h"
#include "ddl/io/image_output.h"
#include "ddl/map/keyframe.h"
#include "ddl/map/map.h"
#include "ddl/map/map_file.h"
#include "ddl/octomap/octree_map.h"

namespace ddl::pipeline {

struct DenseMapperConfig {
  bool inpainting_enabled = true;  // repair keyframes before mapping
  bool octomap_enabled = true;     // build the octree
  bool threaded = false;           // own thread (threaded pipeline mode)
  /// Deterministic mode: the dense stage runs in its own thread all the same, but every pose and
  /// map state it reads is taken when the keyframe is submitted, as the inline stage would read
  /// them, so its outputs do not depend on the thread's timing. An error of the stage then stops
  /// the run at a later keyframe or at its end rather than at the failing keyframe. false =
  /// inline.
  bool deterministic_thread = true;
  std::size_t queue_capacity = 8;  // keyframes waiting for the dense thread
  /// On Linux: nice value of the dense thread (0..19), so that on a machine with few cores
  /// tracking gets the CPU first; the dense work catches up in tracking's idle time.
  int thread_nice = 10;
  std::string save_inpainted_dir;  // non-empty: write repaired keyframes here
  /// Pixels this close outside a keyframe's dynamic mask (object edges the mask missed) are
  /// neither a background source for later keyframes nor put into the octree.
  int mask_border_px = 12;
  /// A keyframe goes into the octree this many keyframes after it was made, so that local BA has
  /// refined its pose by then (it moves keyframes by up to 2 cm on syn_walking_xyz); the last
  /// ones go in when the run ends. 0 = at once. The octree is complete only after finish().
  int octree_delay_keyframes = 10;
  inpainting::InpaintingConfig inpainting;
  octomap::OctreeConfig octree;

  void validate() const;
};

struct DenseKeyframe {
  map::KeyFramePtr keyframe;
  cv::Mat bgr;  // as tracked (undistorted)
  cv::Mat depth_m;
  cv::Mat dynamic_mask;  // combined dynamic mask of the frame (may be empty)
};

/// What the dense stage reads from the map for one step (deterministic_thread), taken in one
/// consistent reading when the step is submitted: the world poses of the keyframes it may use
/// (culled ones resolved through their parents) and the map's big-change index.
struct DensePoseSnapshot {
  int big_change_index = 0;
  std::unordered_map<map::KeyFrameId, SE3> T_w_c;
};

struct DenseStats {
  std::size_t keyframes = 0;
  long masked_pixels = 0;
  long filled_pixels = 0;
  long image_filled_pixels = 0;
  std::size_t octree_rebuilds = 0;
  std::size_t resets = 0;        // map resets: stored keyframes and the octree dropped
  std::size_t scans_loaded = 0;  // dense scans of a loaded map file (preload)
  /// Most bytes the stored keyframes' images held at once: the inpainting sources at full
  /// resolution, older keyframes only with the pixels an octree rebuild uses.
  std::size_t peak_stored_image_bytes = 0;
};

class DenseMapper {
 public:
  DenseMapper(const DenseMapperConfig& config, const camera::PinholeCamera& camera,
              std::shared_ptr<const map::Map> map);
  ~DenseMapper();
  DenseMapper(const DenseMapper&) = delete;
  DenseMapper& operator=(const DenseMapper&) = delete;

  void submit(DenseKeyframe keyframe);
  /// Before the first submit(): the dense scans of a map file loaded into the map
  /// (map::MapFileContents::dense_scans), each anchored to one of its keyframes. They go into the
  /// octree at once and with every rebuild, at their anchor's current pose; they are never
  /// inpainting sources. Without an octree they are ignored. A scan whose pixel step is neither
  /// 1 nor the octree's pixel_stride cannot be integrated: ConfigError naming
  /// dense.octree.pixel_stride. ddl::Error after a submit() or for an anchor not in the map.
  void preload(std::vector<map::DenseScan> scans);
  /// The map was reset (tracking lost before the map had enough keyframes): the keyframes
  /// stored so far live in a world frame that no longer exists, so they are dropped as
  /// inpainting sources and the octree is emptied. Ordered with submit(): in threaded mode it
  /// travels through the queue behind the keyframes submitted before it.
  void reset();
  /// Drains the queue, joins the thread, rebuilds the octree once more if poses moved since
  /// (a big change, or any keyframe moved by more than a quarter voxel).
  void finish();
  /// Writes map.ot, map.bt, map.ply and map_top.png / map_oblique.png into `dir`, each whole or
  /// not at all (core/filesystem.h), and returns the paths written. A file that cannot be written
  /// does not stop the others: its error message is appended to `errors`. Throws OutputError when
  /// `dir` cannot be created.
  std::vector<std::string> write_outputs(const std::string& dir,
                                         std::vector<std::string>& errors) const;

  /// After finish(): every stored keyframe's scan at the octree's pixel stride, anchored to its
  /// nearest keyframe that was not culled (itself, unless culled) with its pose relative to it,
  /// for a map file (map::save_map_file). Empty without an octree; ddl::Error before finish().
  std::vector<map::DenseScan> dense_scans() const;

  DenseStats stats() const;
  /// The repaired keyframes of save_inpainted_dir that could not be written (io/image_output.h).
  std::optional<std::string> saved_images_error() const { return saved_images_.error(); }
  const TimingStats& timings() const { return timings_; }
  const octomap::OctreeMap* octree() const { return octree_.get(); }

 private:
  struct Stored {
    map::KeyFramePtr keyframe;
    cv::Mat bgr;       // repaired
    cv::Mat depth_m;   // repaired
    cv::Mat unfilled;  // still-dynamic pixels
    cv::Mat exclude;   // unfilled and the border band around the mask: not a source, not mapped
    cv::Mat repaired;  // pixels its own repair filled (a source after observed pixels)
    std::shared_ptr<const inpainting::DepthBlocks> blocks;  // of depth_m, for later repairs
    SE3 T_w_c_integrated;     // the pose it went into the octree at (rebuild when it moved)
    bool integrated = false;  // in the octree (octree_delay_keyframes)
    int pixel_step = 1;       // > 1: compacted to the octree's pixels (no longer a source)
    /// Loaded from a map file (preload; the first `loaded_` of stored_): the scan's camera
    /// relative to `keyframe`, its anchor. Identity for the run's own keyframes.
    SE3 T_anchor_c;
  };
  struct ResetRequest {
    std::optional<DensePoseSnapshot> snapshot;
  };
  struct Submitted {
    DenseKeyframe keyframe;
    std::optional<DensePoseSnapshot> snapshot;
  };
  struct Preloaded {
    std::vector<Stored> scans;
    std::optional<DensePoseSnapshot> snapshot;
  };
  using Item = std::variant<Submitted, ResetRequest, Preloaded>;
  /// The poses of `keyframes` and the big-change index now (the caller's thread).
  DensePoseSnapshot take_snapshot(const std::vector<map::KeyFramePtr>& keyframes) const;
  /// The map's big-change index as the current step sees it.
  int big_change_index() const;
  /// Reads the poses of `keyframes` as the current step sees them, in one reading.
  std::vector<SE3> poses_of(const std::vector<map::KeyFramePtr>& keyframes) const;
  void worker();
  void handle(Item item);
  void process(DenseKeyframe item);
  void drop_stored();
  void add_preloaded(std::vector<Stored> scans);
  /// The world pose of a stored keyframe's camera, given its keyframe's (anchor's) pose.
  static SE3 camera_pose(const Stored& s, const SE3& T_w_keyframe) {
    return T_w_keyframe * s.T_anchor_c;
  }
  /// Clears the octree and integrates every stored keyframe but the newest `keep_back` at its
  /// current pose.
  void rebuild_octree(std::size_t keep_back);
  /// Integrates the stored keyframes that are due (all but the newest `keep_back`) and not in
  /// the octree yet; returns how many.
  std::size_t integrate_due(std::size_t keep_back);
  /// Keyframes older than the inpainting sources keep only what an octree rebuild needs (its
  /// pixel_stride's pixels of colour, depth and exclusion mask), or nothing without an octree.
  void compact_old_keyframes();
  /// How many of the newest stored keyframes are inpainting sources (0 without inpainting).
  std::size_t source_window() const;
  /// Whether a stored keyframe's pose moved since it went into the octree by more than a
  /// quarter voxel, at the octree's range (local BA refines poses without a big change).
  bool poses_moved_since_integration() const;

  DenseMapperConfig config_;
  camera::PinholeCamera camera_;
  std::shared_ptr<const map::Map> map_;
  std::unique_ptr<octomap::OctreeMap> octree_;
  std::vector<Stored> stored_;  // all repaired keyframes, in insertion order (loaded ones first)
  std::size_t loaded_ = 0;      // how many of stored_ are loaded scans (at its front)
  bool submitted_any_ = false;
  /// The snapshot the worker's current step reads instead of the map (nullptr: the map).
  const DensePoseSnapshot* snapshot_ = nullptr;
  /// Caller side of deterministic_thread: the keyframes submitted since the last reset, whose
  /// poses a step may read (the worker's stored_ holds the same ones).
  std::vector<map::KeyFramePtr> submitted_;
  int seen_big_change_ = 0;
  TimingStats timings_;
  mutable std::mutex stats_mutex_;
  DenseStats stats_;
  io::ImageOutputLog saved_images_{"the repaired keyframes (--save-inpainted)"};
  std::unique_ptr<BoundedQueue<Item>> queue_;
  std::thread thread_;
  std::exception_ptr error_;
  bool finished_ = false;
};

}  // namespace ddl::pipeline
