#include "ddl/pipeline/local_mapping_gate.h"

namespace ddl::pipeline {

bool LocalMappingGate::open_insertion() {
  std::lock_guard lock(mutex_);
  if (stop_requests_ > 0) return false;
  insertion_open_ = true;
  return true;
}

void LocalMappingGate::close_insertion(bool queued_keyframe) {
  {
    std::lock_guard lock(mutex_);
    insertion_open_ = false;
    if (queued_keyframe) {
      ++pushed_;
      // Mapping still works on an older keyframe: end its local BA early (ORB-SLAM2's
      // InterruptBA). Counted under the mutex, so a keyframe the worker took before this count
      // never aborts its own processing.
      if (taken_ < pushed_) abort_local_ba_.store(true);
    }
  }
  changed_.notify_all();
}

bool LocalMappingGate::mapping_idle() const {
  std::lock_guard lock(mutex_);
  return !worker_exited_ && processed_all();
}

void LocalMappingGate::wait_until_idle() const {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return worker_exited_ || processed_all(); });
}

void LocalMappingGate::begin_keyframe() {
  std::unique_lock lock(mutex_);
  changed_.wait(lock, [&] { return stops_granted_ == 0; });
  ++taken_;
  in_progress_ = true;
  // Decided under the mutex that guards the requests: raised when newer keyframes already wait,
  // or loop closing is waiting for the queue to drain (ORB-SLAM2 skips fusion and local BA then).
  abort_local_ba_.store(taken_ < pushed_ || stop_requests_ > 0);
}

void LocalMappingGate::end_keyframe() {
  {
    std::lock_guard lock(mutex_);
    in_progress_ = false;
  }
  changed_.notify_all();
}

void LocalMappingGate::worker_exited() {
  {
    std::lock_guard lock(mutex_);
    worker_exited_ = true;
    in_progress_ = false;
  }
  changed_.notify_all();
}

bool LocalMappingGate::drained() const {
  return worker_exited_ || (!insertion_open_ && processed_all());
}

void LocalMappingGate::pause() {
  std::unique_lock lock(mutex_);
  ++stop_requests_;
  abort_local_ba_.store(true);  // end a running local BA
  changed_.wait(lock, [&] { return drained(); });
  if (stops_granted_++ == 0) stop_sequence_.fetch_add(1);  // odd: held
}

void LocalMappingGate::resume() {
  {
    std::lock_guard lock(mutex_);
    if (--stops_granted_ == 0) stop_sequence_.fetch_add(1);  // even: released
    --stop_requests_;
  }
  changed_.notify_all();
}

}  // namespace ddl::pipeline
