#pragma once
// Local mapping (ORB-SLAM2 LocalMapping; ORB-SLAM T-RO 2015 section VI): for each new keyframe,
// in order,
//   1. BoW of its features (if the tracker did not compute it), observations of the points it
//      tracked, covisibility update, insertion into the map and the keyframe database;
//   2. culling of recently created points that tracking does not find;
//   3. new points by triangulation with the covisible keyframes;
//   4. fusion of duplicated points with the neighbours (and their neighbours);
//   5. local bundle adjustment;
//   6. culling of redundant covisible keyframes.
// Steps 4 to 6 are skipped, and step 3 cut short, once `abort` is raised (threaded mode: a new
// keyframe is waiting), as ORB-SLAM2 does when new keyframes are queued; local BA also polls it.
//
// Thread-safety: process() is called from one thread at a time (the mapping thread, or the
// caller's thread in deterministic mode); statistics() and request_reset() from any thread.

#include <atomic>
#include <memory>
#include <mutex>
#include <optional>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/map/map.h"
#include "ddl/mapping/local_ba.h"
#include "ddl/mapping/local_mapper_config.h"
#include "ddl/mapping/point_culling.h"
#include "ddl/vocabulary/bow_database.h"
#include "ddl/vocabulary/vocabulary.h"

namespace ddl::mapping {

/// Wall-clock time of each step of one process() call [ms].
/// Stages that did not run to completion for a keyframe (stopped by the abort flag; local BA
/// off or with too few keyframes) are empty.
struct LocalMapperTimings {
  double insertion_ms = 0.0;  // BoW, observations, covisibility, database
  double point_culling_ms = 0.0;
  double triangulation_ms = 0.0;
  std::optional<double> fusion_ms;
  std::optional<double> local_ba_ms;  // including the gathering and the write-back
  std::optional<double> keyframe_culling_ms;
};

/// Counters over all keyframes processed so far.
struct LocalMapperStatistics {
  std::size_t keyframes_processed = 0;
  std::size_t points_created = 0;  // by triangulation
  std::size_t points_culled = 0;   // recent points removed
  std::size_t points_fused = 0;    // fusions and added observations
  std::size_t keyframes_culled = 0;
  std::size_t local_ba_runs = 0;
  std::size_t local_ba_aborted = 0;
  std::size_t outliers_erased = 0;  // associations removed after local BA
  LocalBaStatistics last_local_ba;
  /// Of the last process() call; empty when that call dropped its keyframe unprocessed.
  std::optional<LocalMapperTimings> last_timings;
};

class LocalMapper {
 public:
  /// Validates the config (throws ddl::ConfigError naming the key). `camera` is the undistorted
  /// camera the keyframes' keypoints live in.
  LocalMapper(const LocalMapperConfig& config, const camera::PinholeCamera& camera,
              std::shared_ptr<map::Map> map,
              std::shared_ptr<const vocabulary::Vocabulary> vocabulary,
              std::shared_ptr<vocabulary::BowDatabase> keyframe_database);

  /// Processes one new keyframe completely; `abort` (may be null) is polled by local BA to stop
  /// early. Returns the keyframe as it should go to loop closing (nullptr if it was culled).
  map::KeyFramePtr process(const map::KeyFramePtr& keyframe, const std::atomic<bool>* abort);

  /// The tracker cleared the map (TrackingResult::map_reset): before the next keyframe the points
  /// on probation are forgotten, and keyframes with ids below `first_valid_keyframe` (made for
  /// the old map, possibly still queued) are dropped by process() (ORB-SLAM2
  /// LocalMapping::RequestReset).
  void request_reset(map::KeyFrameId first_valid_keyframe);

  LocalMapperStatistics statistics() const;
  const LocalMapperConfig& config() const { return config_; }

 private:
  void apply_pending_reset();
  /// False when the map refused the keyframe (it belongs to a map that was reset meanwhile).
  bool insert_keyframe(const map::KeyFramePtr& keyframe);
  int fuse_with_neighbours(const map::KeyFramePtr& keyframe);

  LocalMapperConfig config_;
  CameraIntrinsics camera_;
  double close_depth_m_;
  std::shared_ptr<map::Map> map_;
  std::shared_ptr<const vocabulary::Vocabulary> vocabulary_;
  std::shared_ptr<vocabulary::BowDatabase> database_;
  RecentPoints recent_points_;
  map::KeyFrameId first_valid_keyframe_ = 0;  // older keyframes belong to a cleared map

  std::mutex reset_mutex_;  // guards pending_reset_
  std::optional<map::KeyFrameId> pending_reset_;
  mutable std::mutex stats_mutex_;
  LocalMapperStatistics stats_;
};

}  // namespace ddl::mapping
