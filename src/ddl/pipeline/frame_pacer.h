#pragma once
// Feeds a recorded sequence at the pace of a live camera: the frame stamped t is released no
// earlier than start + (t - t0) / rate, where t0 is the first frame's stamp and start the wall
// time at which it was released. rate 1 is real time, 2 twice as fast. No frame is dropped: a
// frame that is due already goes at once, and the pipeline falls behind (FramePrefetcher's live
// mode drops frames instead). The schedule is absolute, as a camera's: after a stall the overdue
// frames follow each other at once. ORB-SLAM2's rgbd_tum example paces relatively instead (it
// sleeps after each frame for what is left of its interval); the two agree while the pipeline
// keeps up. latency_ms() tells how far behind a frame was handled.
// Thread-safety: wait_for() from one thread, the other methods from any.

#include <atomic>
#include <chrono>
#include <condition_variable>
#include <mutex>
#include <optional>

namespace ddl::pipeline {

class FramePacer {
 public:
  using Clock = std::chrono::steady_clock;
  static constexpr double kMinRate = 1e-3;
  static constexpr double kMaxRate = 1e3;

  /// `rate` in [kMinRate, kMaxRate] (ConfigError naming --playback-rate otherwise). `stop` (may
  /// be null) ends a wait early, like cancel().
  explicit FramePacer(double rate, const std::atomic<bool>* stop = nullptr);

  /// Blocks until the frame stamped `timestamp_s` is due: true. False when cancel() or `stop`
  /// ended the wait (the frame is not due; the caller should stop). A frame stamped before the
  /// first one is due at once.
  bool wait_for(double timestamp_s);

  /// Whether the frame stamped `timestamp_s` is due now (false before the first frame was
  /// released).
  bool is_due(double timestamp_s) const;

  /// Milliseconds from the moment the frame stamped `timestamp_s` was due to `now`; 0 before the
  /// first frame was released.
  double latency_ms(double timestamp_s, Clock::time_point now = Clock::now()) const;

  /// Ends the current and every later wait at once (the pipeline is shutting down).
  void cancel();

 private:
  Clock::time_point due(double timestamp_s) const;

  double rate_;
  const std::atomic<bool>* stop_;
  mutable std::mutex mutex_;
  std::condition_variable wake_;
  bool cancelled_ = false;
  std::optional<double> first_stamp_s_;
  Clock::time_point start_;
};

}  // namespace ddl::pipeline
