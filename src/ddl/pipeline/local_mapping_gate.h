#pragma once
// The stop handshake between tracking, the local-mapping worker and loop closing in threaded
// mode (ORB-SLAM2's LocalMapping RequestStop / Stop / SetNotStop):
//
//   loop closing   pause(): requests the stop, so tracking creates no more keyframes and a
//                  running local BA ends early; waits until every keyframe handed to mapping so
//                  far is processed (it is then in the map, with its parent and covisibility
//                  links, and the correction moves it); then holds the worker. resume() lets go.
//   tracking       open_insertion() before the keyframe decision: false while a stop is
//                  requested (decide with MappingStatus::stopped). close_insertion() after the
//                  keyframe, if any, was queued. A stop is not granted while an insertion is open.
//   mapping worker begin_keyframe() after taking a keyframe off the queue: blocks while mapping is
//                  held, and decides the keyframe's local-BA abort flag. end_keyframe() after
//                  processing it; worker_exited() when the worker ends (normally or on error).
//
// Until 2026-11-26 the pause only waited for the keyframe in progress, so up to
// keyframe_queue_capacity keyframes still waiting in the queue missed a loop correction or a
// global-BA merge: without covisibility links yet, neither the essential graph nor the
// spanning-tree walk reached them, and they entered the map uncorrected (found by review).
//
// Thread-safety: every member may be called from any thread.

#include <atomic>
#include <condition_variable>
#include <cstdint>
#include <mutex>

namespace ddl::pipeline {

class LocalMappingGate {
 public:
  // Tracking side.
  /// False while loop closing asks mapping to stop: create no keyframe. Pair every call with
  /// close_insertion(), whatever it returned.
  bool open_insertion();
  /// `queued_keyframe`: a keyframe was pushed to the mapping queue since open_insertion().
  void close_insertion(bool queued_keyframe);

  // Mapping worker side.
  /// Blocks while loop closing holds mapping; then counts the keyframe as taken.
  void begin_keyframe();
  void end_keyframe();
  /// The worker will take no more keyframes; a pause no longer waits for the queue.
  void worker_exited();
  /// Whether every keyframe queued so far is processed and none is in progress: tracking's
  /// "mapping accepts keyframes" (ORB-SLAM2 AcceptKeyFrames). Counted under the gate's mutex, so a
  /// keyframe the worker has taken off the queue but not yet begun counts as work (until stop 30
  /// System read the queue's size and a busy flag the worker set after taking it, which left a
  /// moment in which a keyframe in flight looked idle). False once the worker has exited.
  bool mapping_idle() const;
  /// Blocks until mapping_idle() holds or the worker has exited.
  void wait_until_idle() const;
  /// Polled by local BA: raised when a newer keyframe is queued or loop closing asks to stop.
  const std::atomic<bool>* abort_flag() const { return &abort_local_ba_; }

  // Loop-closing side (LoopCloser::MappingPause hooks). Pauses may nest.
  void pause();
  void resume();

  /// Odd while loop closing holds mapping (and may be moving keyframes), incremented when a stop
  /// begins and when it ends. A reader that combines poses read at different times (the
  /// geometry check: the frame's pose, then the reference keyframes') saw no loop correction or
  /// global-BA merge in between when its two readings are equal and even (unchanged()).
  std::uint64_t stop_sequence() const { return stop_sequence_.load(); }
  static bool unchanged(std::uint64_t before, std::uint64_t after) {
    return before == after && before % 2 == 0;
  }

 private:
  bool drained() const;  // under mutex_
  /// Every keyframe queued so far is processed and none is in progress (under mutex_).
  bool processed_all() const { return !in_progress_ && taken_ >= pushed_; }

  mutable std::mutex mutex_;
  mutable std::condition_variable changed_;
  int stop_requests_ = 0;  // pause() calls not yet resumed
  int stops_granted_ = 0;  // ... of which hold mapping now
  bool insertion_open_ = false;
  bool in_progress_ = false;
  bool worker_exited_ = false;
  std::uint64_t pushed_ = 0;  // keyframes queued by tracking
  std::uint64_t taken_ = 0;   // keyframes taken by the worker
  std::atomic<bool> abort_local_ba_{false};
  std::atomic<std::uint64_t> stop_sequence_{0};  // changed under mutex_
};

/// Tracking's insertion window as a scope: opened by the constructor (when `gate` is not null),
/// closed by close() or at the latest by the destructor, so an exception cannot leave it open.
class InsertionWindow {
 public:
  explicit InsertionWindow(LocalMappingGate* gate)
      : gate_(gate), allowed_(gate == nullptr || gate->open_insertion()) {}
  ~InsertionWindow() { close(false); }
  InsertionWindow(const InsertionWindow&) = delete;
  InsertionWindow& operator=(const InsertionWindow&) = delete;

  /// False while loop closing asks mapping to stop.
  bool allowed() const { return allowed_; }
  /// Idempotent; `queued_keyframe` as LocalMappingGate::close_insertion().
  void close(bool queued_keyframe) {
    if (gate_ == nullptr) return;
    gate_->close_insertion(queued_keyframe);
    gate_ = nullptr;
  }

 private:
  LocalMappingGate* gate_;
  bool allowed_;
};

}  // namespace ddl::pipeline
