#include "ddl/loop/loop_closer.h"

#include <spdlog/spdlog.h>

#include "ddl/core/error.h"
#include "ddl/core/timing.h"
#include "ddl/loop/global_ba.h"
#include "ddl/loop/loop_verification.h"

namespace ddl::loop {
namespace {

/// Runs pause() now and resume() when it goes out of scope.
class PauseScope {
 public:
  explicit PauseScope(const MappingPause& hooks) : hooks_(hooks) {
    if (hooks_.pause) hooks_.pause();
  }
  ~PauseScope() {
    if (hooks_.resume) hooks_.resume();
  }
  PauseScope(const PauseScope&) = delete;
  PauseScope& operator=(const PauseScope&) = delete;

 private:
  const MappingPause& hooks_;
};

}  // namespace

LoopCloser::LoopCloser(const LoopCloserConfig& config, const camera::PinholeCamera& camera,
                       std::shared_ptr<map::Map> map,
                       std::shared_ptr<const vocabulary::Vocabulary> vocabulary,
                       std::shared_ptr<vocabulary::BowDatabase> keyframe_database)
    : config_(config),
      camera_(mapping::make_intrinsics(camera, config.bf)),
      map_(std::move(map)),
      vocabulary_(std::move(vocabulary)),
      database_(std::move(keyframe_database)),
      detector_(config.detection, map_, database_) {
  config_.validate();
  if (!map_ || !database_) throw Error("LoopCloser: map and keyframe database are required");
}

LoopCloser::~LoopCloser() {
  try {
    stop();
  } catch (...) {
    spdlog::error("LoopCloser: error while stopping global BA");
  }
}

void LoopCloser::set_mapping_pause(MappingPause hooks) { pause_ = std::move(hooks); }

void LoopCloser::release(const map::KeyFramePtr& keyframe) {
  keyframe->set_not_erase(false);
  // Culling that was deferred while the keyframe was protected happens now.
  if (keyframe->is_bad()) {
    map_->erase_keyframe(keyframe->id());
    database_->erase(keyframe->id());
  }
}

LoopResult LoopCloser::process(const map::KeyFramePtr& keyframe) {
  rethrow_global_ba_error();
  LoopResult result;
  if (!config_.enabled || !keyframe || keyframe->is_bad()) return result;
  result.keyframe = keyframe->id();

  Stopwatch watch;
  keyframe->set_not_erase(true);
  const std::vector<map::KeyFramePtr> candidates = detector_.detect(keyframe);
  result.candidates = candidates.size();
  if (candidates.empty()) {
    release(keyframe);
    result.detection_ms = watch.elapsed_ms();
    return result;
  }
  for (const map::KeyFramePtr& kf : candidates) kf->set_not_erase(true);
  std::optional<LoopMatch> loop = verify_loop_candidates(keyframe, candidates, camera_,
                                                         config_.verification, config_.optimizer);
  for (const map::KeyFramePtr& kf : candidates) {
    if (!loop || kf != loop->matched) release(kf);
  }
  result.detection_ms = watch.elapsed_ms();
  if (!loop) {
    release(keyframe);
    return result;
  }

  // A global BA of an earlier loop is outdated now (ORB-SLAM2 aborts it too).
  abort_global_ba();
  watch.reset();
  {
    PauseScope paused(pause_);
    result.correction =
        correct_loop(keyframe, *loop, *map_, camera_, config_.correction, config_.optimizer);
  }
  result.correction_ms = watch.elapsed_ms();
  // The loop edges protect both keyframes from now on; release our own protection.
  keyframe->set_not_erase(false);
  loop->matched->set_not_erase(false);
  detector_.set_last_loop_keyframe(keyframe->id());
  result.loop_closed = true;
  result.matched_keyframe = loop->matched->id();
  result.loop_matches = loop->loop_matches;
  result.T_cur_matched = loop->T_cur_matched;
  loops_closed_.fetch_add(1);

  if (!config_.global_ba) return result;
  if (config_.global_ba_in_background) {
    std::lock_guard lock(thread_mutex_);
    if (global_ba_thread_.joinable()) global_ba_thread_.join();  // joined above already
    global_ba_abort_.store(false);
    global_ba_running_.store(true);
    global_ba_thread_ = std::thread([this] {
      try {
        run_and_merge_global_ba(&global_ba_abort_);
      } catch (...) {
        std::lock_guard error_lock(error_mutex_);
        global_ba_error_ = std::current_exception();
      }
      global_ba_running_.store(false);
    });
    result.global_ba_started = true;
  } else {
    watch.reset();
    result.global_ba_ran = run_and_merge_global_ba(nullptr);
    result.global_ba_ms = watch.elapsed_ms();
  }
  return result;
}

bool LoopCloser::run_and_merge_global_ba(const std::atomic<bool>* abort) {
  const GlobalBaResult result =
      run_global_bundle_adjustment(*map_, camera_, config_.optimizer, abort);
  if (result.aborted || (abort != nullptr && abort->load())) {
    global_ba_aborted_.fetch_add(1);
    spdlog::info("global BA aborted");
    return false;
  }
  std::size_t updated = 0;
  {
    PauseScope paused(pause_);
    updated = merge_global_bundle_adjustment(*map_, result);
  }
  global_ba_runs_.fetch_add(1);
  spdlog::info("global BA: {} keyframes, {} points, {} iterations, cost {:.4g} -> {:.4g}", updated,
               result.points_w.size(), result.iterations, result.initial_cost, result.final_cost);
  return true;
}

void LoopCloser::abort_global_ba() {
  global_ba_abort_.store(true);
  join_global_ba();
}

void LoopCloser::join_global_ba() {
  std::lock_guard lock(thread_mutex_);
  if (global_ba_thread_.joinable()) global_ba_thread_.join();
}

void LoopCloser::stop() { abort_global_ba(); }

void LoopCloser::wait_for_global_ba() {
  join_global_ba();
  rethrow_global_ba_error();
}

void LoopCloser::rethrow_global_ba_error() {
  std::exception_ptr error;
  {
    std::lock_guard lock(error_mutex_);
    std::swap(error, global_ba_error_);
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace ddl::loop
