#include "ddl/loop/loop_closer.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <vector>

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

/// The keyframes process() protects from culling while it works with them (ORB-SLAM2's
/// SetNotErase / SetErase). Whatever is still protected when the scope ends, also on an exception,
/// is released: culling deferred meanwhile happens then.
class LoopCloser::Protection {
 public:
  explicit Protection(LoopCloser& closer) : closer_(closer) {}
  ~Protection() {
    for (const map::KeyFramePtr& keyframe : keyframes_) {
      try {
        closer_.release(keyframe);
      } catch (...) {
        keyframe->set_not_erase(false);
      }
    }
  }
  Protection(const Protection&) = delete;
  Protection& operator=(const Protection&) = delete;

  void protect(const map::KeyFramePtr& keyframe) {
    keyframe->set_not_erase(true);
    keyframes_.push_back(keyframe);
  }
  /// Releases every protected keyframe except those in `keep`, which stay protected.
  void release_all_but(const std::vector<map::KeyFramePtr>& keep) {
    std::vector<map::KeyFramePtr> kept;
    for (const map::KeyFramePtr& keyframe : keyframes_) {
      if (std::find(keep.begin(), keep.end(), keyframe) != keep.end()) {
        kept.push_back(keyframe);
      } else {
        closer_.release(keyframe);
      }
    }
    keyframes_ = std::move(kept);
  }
  /// The loop edges protect the loop's two keyframes from now on: release() leaves a keyframe
  /// with loop edges protected. One the correction gave no edge is released like any other, its
  /// deferred cull included, and leaves the map and the database (review, stop 26: it was culled
  /// without leaving them).
  void hand_over_to_loop_edges() { release_all_but({}); }

 private:
  LoopCloser& closer_;
  std::vector<map::KeyFramePtr> keyframes_;
};

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

void LoopCloser::request_reset(map::KeyFrameId first_valid_keyframe) {
  {
    std::lock_guard lock(reset_mutex_);
    pending_reset_ = first_valid_keyframe;
  }
  // A global BA of the cleared map has nothing left to refine (nor to merge into).
  global_ba_abort_.store(true);
}

void LoopCloser::on_loop_verified(const map::KeyFramePtr& /*keyframe*/, const LoopMatch& /*loop*/) {
}

void LoopCloser::apply_pending_reset() {
  std::optional<map::KeyFrameId> reset;
  {
    std::lock_guard lock(reset_mutex_);
    std::swap(reset, pending_reset_);
  }
  if (!reset) return;
  first_valid_keyframe_ = std::max(first_valid_keyframe_, *reset);
  detector_.reset(first_valid_keyframe_);
}

bool LoopCloser::confirmed_by_covisibles(const map::KeyFramePtr& keyframe,
                                         const LoopMatch& loop) const {
  const auto needed = static_cast<std::size_t>(config_.detection.covisible_confirmations);
  const std::vector<map::KeyFramePtr> neighbours = keyframe->best_covisibles(needed);
  std::string counts;
  std::size_t confirmed = 0;
  for (const map::KeyFramePtr& neighbour : neighbours) {
    const int inliers = confirm_loop_in(neighbour, keyframe, loop, camera_, config_.verification,
                                        config_.optimizer);
    counts += fmt::format(" {}:{}", neighbour->id(), inliers);
    if (inliers >= config_.verification.min_confirmation_inliers) ++confirmed;
  }
  spdlog::debug("loop confirmation: keyframe {} vs {}: inliers in covisibles{} ({} of {} needed)",
                keyframe->id(), loop.matched->id(), counts, confirmed, needed);
  return confirmed >= needed;
}

void LoopCloser::release(const map::KeyFramePtr& keyframe) {
  if (keyframe->release_erase_protection()) {
    // Culling that was deferred while the keyframe was protected happens now, on this thread:
    // with local mapping paused, so that it does not link a new keyframe to this one or fuse
    // points into it while it is taken apart (review, stop 25). Should mapping cull it first,
    // now that it is free, set_bad() does nothing here.
    PauseScope paused(pause_);
    keyframe->set_bad();
  }
  if (keyframe->is_bad()) {
    map_->erase_culled_keyframe(keyframe);  // with the points it left without observers
    database_->erase(keyframe->id());
  }
}

LoopResult LoopCloser::process(const map::KeyFramePtr& keyframe) {
  rethrow_global_ba_error();
  apply_pending_reset();
  LoopResult result;
  if (!config_.enabled || !keyframe || keyframe->is_bad()) return result;
  if (keyframe->id() < first_valid_keyframe_) return result;
  result.keyframe = keyframe->id();

  // A background global BA may merge while the candidates are verified below; verification
  // then reads poses and points from both sides of the merge. The index tells (checked once the
  // global BA is aborted and joined, when nothing else can move the map).
  const int big_change_before = map_->big_change_index();
  Stopwatch watch;
  Protection protection(*this);
  protection.protect(keyframe);
  const LoopDetector::Detection detection = detector_.detect(keyframe);
  const bool try_pending =
      config_.detection.covisible_confirmations > 0 && !detection.pending.empty();
  std::vector<map::KeyFramePtr> candidates = detection.consistent;
  if (try_pending) {
    candidates.insert(candidates.end(), detection.pending.begin(), detection.pending.end());
  }
  result.candidates = candidates.size();
  if (candidates.empty()) {
    result.detection_ms = watch.elapsed_ms();
    return result;
  }
  for (const map::KeyFramePtr& kf : candidates) protection.protect(kf);
  std::optional<LoopMatch> loop;
  if (!detection.consistent.empty()) {
    loop = verify_loop_candidates(keyframe, detection.consistent, camera_, config_.verification,
                                  config_.optimizer);
  }
  if (!loop && try_pending) {
    // Not consistent over time yet: accepted when the covisibles confirm the loop geometrically.
    loop = verify_loop_candidates(keyframe, detection.pending, camera_, config_.verification,
                                  config_.optimizer);
    if (loop && !confirmed_by_covisibles(keyframe, *loop)) loop.reset();
  }
  result.detection_ms = watch.elapsed_ms();
  if (!loop) return result;  // the protection scope releases every keyframe
  // The keyframe and the loop keyframe stay protected until the loop edges protect them; the
  // other candidates are free again (and culling deferred on them happens now).
  protection.release_all_but({keyframe, loop->matched});
  on_loop_verified(keyframe, *loop);

  // A global BA of an earlier loop is outdated now (ORB-SLAM2 aborts it too).
  abort_global_ba();
  if (map_->big_change_index() != big_change_before) {
    // It merged during the verification: T_cur_w_corrected is in the world frame from before.
    // The detector keeps its consistent groups, so a later keyframe finds the loop again.
    loops_deferred_.fetch_add(1);
    result.deferred_after_merge = true;
    spdlog::info(
        "loop at keyframe {} with {} left for later: a global BA merged while it was verified",
        keyframe->id(), loop->matched->id());
    return result;
  }
  watch.reset();
  {
    PauseScope paused(pause_);
    if (keyframe->is_bad() || loop->matched->is_bad()) {
      // Culling that began before they were protected (the keyframe is checked before
      // protect(), the candidates come from detect()) can have taken them.
      spdlog::info("loop at keyframe {} with {} dropped: a keyframe left the map", keyframe->id(),
                   loop->matched->id());
      return result;
    }
    result.correction =
        correct_loop(keyframe, *loop, *map_, camera_, config_.correction, config_.optimizer);
  }
  result.correction_ms = watch.elapsed_ms();
  protection.hand_over_to_loop_edges();
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
  if (result.failed) {
    spdlog::warn("global BA failed (Ceres); its result is not merged");
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
