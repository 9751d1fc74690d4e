#include "ddl/pipeline/frame_pacer.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "ddl/core/error.h"

namespace ddl::pipeline {
namespace {

// How often a wait looks at the caller's stop flag (Ctrl-C sets it from a signal handler, which
// cannot notify a condition variable).
constexpr auto kStopPollInterval = std::chrono::milliseconds(50);

}  // namespace

FramePacer::FramePacer(double rate, const std::atomic<bool>* stop) : rate_(rate), stop_(stop) {
  if (!(rate >= kMinRate && rate <= kMaxRate)) {  // NaN fails too
    throw ConfigError::for_key(
        "--playback-rate", fmt::format("must be in [{}, {}], got {}", kMinRate, kMaxRate, rate));
  }
}

FramePacer::Clock::time_point FramePacer::due(double timestamp_s) const {
  // Clamped to a year: a wild stamp must not overflow the clock's 64-bit nanoseconds.
  constexpr double kMaxOffsetS = 365.0 * 24.0 * 3600.0;
  const double offset_s = std::clamp((timestamp_s - *first_stamp_s_) / rate_, 0.0, kMaxOffsetS);
  return start_ +
         std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(offset_s));
}

bool FramePacer::wait_for(double timestamp_s) {
  std::unique_lock lock(mutex_);
  const auto ended = [&] { return cancelled_ || (stop_ != nullptr && stop_->load()); };
  if (ended()) return false;
  if (!first_stamp_s_) {
    first_stamp_s_ = timestamp_s;
    start_ = Clock::now();
    return true;
  }
  const Clock::time_point until = due(timestamp_s);
  while (!ended()) {
    const Clock::time_point now = Clock::now();
    if (now >= until) return true;
    wake_.wait_until(lock, std::min(until, now + kStopPollInterval));
  }
  return false;
}

bool FramePacer::is_due(double timestamp_s) const {
  std::lock_guard lock(mutex_);
  return first_stamp_s_ && Clock::now() >= due(timestamp_s);
}

double FramePacer::latency_ms(double timestamp_s, Clock::time_point now) const {
  std::lock_guard lock(mutex_);
  if (!first_stamp_s_) return 0.0;
  return std::chrono::duration<double, std::milli>(now - due(timestamp_s)).count();
}

void FramePacer::cancel() {
  {
    std::lock_guard lock(mutex_);
    cancelled_ = true;
  }
  wake_.notify_all();
}

}  // namespace ddl::pipeline
