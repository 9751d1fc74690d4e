#pragma once
// Loop closing (ORB-SLAM2 LoopClosing; ORB-SLAM T-RO 2015 section VII) for RGB-D, scale fixed:
// detection (loop_detector.h), verification by 3D-3D RANSAC and projection matching
// (loop_verification.h), correction with loop fusion and essential-graph optimisation
// (loop_corrector.h), then global bundle adjustment (global_ba.h).
//
// Acceptance: candidates consistent over consecutive keyframes (ORB-SLAM2's rule) are verified
// first. RGB-D keyframes are sparse (a keyframe every 1-1.5 s on a slow walk), so a revisit may
// span fewer keyframes than that rule needs; a candidate that is not consistent yet is therefore
// also accepted when its verified loop holds in the keyframe's best covisibles as well
// (ORB-SLAM3's verification in the covisibility graph; detection.covisible_confirmations).
//
// Modes: with global_ba_in_background = false (deterministic mode) global BA runs inline in
// process(). With true (threaded mode) it runs in a thread owned by the LoopCloser; a later loop,
// stop() or the destructor aborts it through an atomic flag read by a Ceres iteration callback
// and joins it; wait_for_global_ba() lets it finish. Its result is merged as ORB-SLAM2 does
// (global_ba.h), with local mapping held still through the MappingPause hooks.
//
// Thread-safety: process() from one thread (the loop thread, or the caller's in deterministic
// mode); set_mapping_pause() before the first process(); stop(), wait_for_global_ba(),
// request_reset() and the counters from any thread. Errors of the background global BA are rethrown
// by the next process() or wait_for_global_ba().

#include <atomic>
#include <exception>
#include <functional>
#include <memory>
#include <mutex>
#include <optional>
#include <thread>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/loop/loop_closer_config.h"
#include "ddl/loop/loop_corrector.h"
#include "ddl/loop/loop_detector.h"
#include "ddl/loop/loop_verification.h"
#include "ddl/map/map.h"
#include "ddl/vocabulary/bow_database.h"
#include "ddl/vocabulary/vocabulary.h"

namespace ddl::loop {

/// Outcome of process() for one keyframe.
struct LoopResult {
  bool loop_closed = false;
  map::KeyFrameId keyframe = 0;          ///< the keyframe processed
  map::KeyFrameId matched_keyframe = 0;  ///< the loop keyframe (when loop_closed)
  std::size_t candidates = 0;            ///< consistent candidates verified
  int loop_matches = 0;                  ///< verified matches with the loop points
  SE3 T_cur_matched;                     ///< relative pose estimated (when loop_closed)
  LoopCorrectionStatistics correction;   ///< when loop_closed
  /// A loop was verified, but a background global BA merged into the map while it was being
  /// verified: its poses and points were read from both sides of the merge, so the loop is left
  /// for a later keyframe to detect again (loop_closed stays false).
  bool deferred_after_merge = false;
  bool global_ba_started = false;  ///< in the background thread
  bool global_ba_ran = false;      ///< inline, completed and merged
  double detection_ms = 0.0;       ///< detection and verification
  double correction_ms = 0.0;
  double global_ba_ms = 0.0;  ///< inline global BA (0 in background mode)
};

/// Hooks that keep local mapping still while loop closing moves the map (ORB-SLAM2's
/// RequestStop / Release). pause() must return once every keyframe handed to local mapping so
/// far is processed (in the map, with its covisibility links, so the correction reaches it), and
/// local mapping must start no other until resume() (pipeline::LocalMappingGate); both may be
/// called from the loop thread and from the global BA thread. Empty hooks (deterministic mode)
/// do nothing.
struct MappingPause {
  std::function<void()> pause;
  std::function<void()> resume;
};

class LoopCloser {
 public:
  /// Validates the config (throws ddl::ConfigError naming the key). `camera` is the undistorted
  /// camera of the keyframes.
  LoopCloser(const LoopCloserConfig& config, const camera::PinholeCamera& camera,
             std::shared_ptr<map::Map> map,
             std::shared_ptr<const vocabulary::Vocabulary> vocabulary,
             std::shared_ptr<vocabulary::BowDatabase> keyframe_database);
  /// Aborts and joins a running global BA.
  virtual ~LoopCloser();
  LoopCloser(const LoopCloser&) = delete;
  LoopCloser& operator=(const LoopCloser&) = delete;

  void set_mapping_pause(MappingPause hooks);

  /// The tracker cleared the map (TrackingResult::map_reset): before the next keyframe the
  /// detector forgets its consistent groups, and keyframes with ids below `first_valid_keyframe`
  /// (made for the old map, possibly still queued) are ignored by process() (ORB-SLAM2
  /// LoopClosing::RequestReset). A background global BA of the old map is told to abort (it
  /// stops at its next iteration and merges nothing); this call does not wait for it.
  void request_reset(map::KeyFrameId first_valid_keyframe);

  /// Detects and, when verified, corrects a loop at `keyframe` (processed by local mapping
  /// first: it must have its BoW and be in the database); then global BA inline, or started in
  /// the background.
  LoopResult process(const map::KeyFramePtr& keyframe);

  /// Aborts a running background global BA and joins its thread (no merge). For shutdown on
  /// error or destruction; at the normal end of a sequence call wait_for_global_ba() instead.
  void stop();
  /// Blocks until a running background global BA has finished and merged; rethrows its error.
  void wait_for_global_ba();
  bool global_ba_running() const { return global_ba_running_.load(); }

  std::size_t loops_closed() const { return loops_closed_.load(); }
  /// Global BAs completed and merged (inline or background).
  std::size_t global_ba_runs() const { return global_ba_runs_.load(); }
  /// Global BAs aborted by a newer loop, a map reset or stop().
  std::size_t global_ba_aborted() const { return global_ba_aborted_.load(); }
  /// Verified loops left for later because a global BA merged during their verification.
  std::size_t loops_deferred() const { return loops_deferred_.load(); }

 protected:
  /// Called by process() once a loop is verified at `keyframe`, before a running global BA is
  /// aborted and the loop corrected. No-op; a seam for tests and instrumentation (tests use it
  /// to merge a global BA at exactly this point).
  virtual void on_loop_verified(const map::KeyFramePtr& keyframe, const LoopMatch& loop);

 private:
  void apply_pending_reset();
  /// True when the loop verified at `keyframe` holds in its covisible_confirmations best
  /// covisibles too (each with >= min_confirmation_inliers inliers).
  bool confirmed_by_covisibles(const map::KeyFramePtr& keyframe, const LoopMatch& loop) const;
  class Protection;
  void release(const map::KeyFramePtr& keyframe);
  void abort_global_ba();
  void join_global_ba();
  void rethrow_global_ba_error();
  bool run_and_merge_global_ba(const std::atomic<bool>* abort);

  LoopCloserConfig config_;
  mapping::CameraIntrinsics camera_;
  std::shared_ptr<map::Map> map_;
  std::shared_ptr<const vocabulary::Vocabulary> vocabulary_;
  std::shared_ptr<vocabulary::BowDatabase> database_;
  LoopDetector detector_;
  MappingPause pause_;
  map::KeyFrameId first_valid_keyframe_ = 0;  // older keyframes belong to a cleared map
  std::mutex reset_mutex_;                    // guards pending_reset_
  std::optional<map::KeyFrameId> pending_reset_;

  std::atomic<std::size_t> loops_closed_{0};
  std::atomic<std::size_t> global_ba_runs_{0};
  std::atomic<std::size_t> global_ba_aborted_{0};
  std::atomic<std::size_t> loops_deferred_{0};

  std::mutex thread_mutex_;  // guards global_ba_thread_ (start / join)
  std::thread global_ba_thread_;
  std::atomic<bool> global_ba_abort_{false};
  std::atomic<bool> global_ba_running_{false};
  std::mutex error_mutex_;
  std::exception_ptr global_ba_error_;
};

}  // namespace ddl::loop
