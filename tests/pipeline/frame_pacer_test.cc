// FramePacer: frames released at the pace of their stamps, late ones at once, waits that end on
// cancel() or the stop flag. Time bounds are one-sided where the pacing guarantees them and
// generous (seconds) where a loaded machine could delay a thread.

#include "ddl/pipeline/frame_pacer.h"

#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <limits>
#include <string>
#include <thread>

#include "ddl/core/error.h"

namespace ddl::pipeline {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

TEST(FramePacer, ARateThatIsNotPositiveIsAConfigErrorNamingTheOption) {
  for (double rate : {0.0, -1.0, 1e-4, 2000.0, std::numeric_limits<double>::quiet_NaN(),
                      std::numeric_limits<double>::infinity()}) {
    try {
      FramePacer pacer(rate);
      ADD_FAILURE() << "no error for " << rate;
    } catch (const ConfigError& e) {
      EXPECT_NE(std::string(e.what()).find("--playback-rate"), std::string::npos) << e.what();
    }
  }
}

TEST(FramePacer, FramesAreReleasedAtTheirStampsDividedByTheRate) {
  FramePacer pacer(2.0);
  const Clock::time_point start = Clock::now();
  EXPECT_TRUE(pacer.wait_for(100.0));  // the first frame goes at once and sets the clock
  EXPECT_LT(seconds_since(start), 1.0);
  for (double stamp : {100.1, 100.2, 100.3}) EXPECT_TRUE(pacer.wait_for(stamp));
  // The last frame is due 0.3 s / 2 after the first.
  const double elapsed = seconds_since(start);
  EXPECT_GE(elapsed, 0.15);
  EXPECT_LT(elapsed, 3.0);
  // Handled right after its release: the latency is small and never negative beyond rounding.
  EXPECT_GT(pacer.latency_ms(100.3), -1.0);
  EXPECT_LT(pacer.latency_ms(100.3), 3000.0);
}

TEST(FramePacer, AFrameThatIsDueAlreadyGoesAtOnceAndItsLatencyShowsIt) {
  FramePacer pacer(1.0);
  pacer.wait_for(5.0);
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  const Clock::time_point before = Clock::now();
  EXPECT_TRUE(pacer.wait_for(5.1));  // due 0.1 s after the first: 0.2 s late
  EXPECT_LT(seconds_since(before), 1.0);
  EXPECT_GE(pacer.latency_ms(5.1, before), 190.0);
  // A stamp before the first one is due at the start.
  EXPECT_GE(pacer.latency_ms(4.0, before), 290.0);
}

TEST(FramePacer, CancelAndTheStopFlagEndAWaitAtOnce) {
  {
    FramePacer pacer(1.0);
    pacer.wait_for(0.0);
    std::thread canceller([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      pacer.cancel();
    });
    const Clock::time_point start = Clock::now();
    EXPECT_FALSE(pacer.wait_for(30.0));
    EXPECT_LT(seconds_since(start), 5.0);
    canceller.join();
    EXPECT_FALSE(pacer.wait_for(31.0));  // later waits end at once too
    EXPECT_LT(seconds_since(start), 5.0);
  }
  {
    std::atomic<bool> stop{false};
    FramePacer pacer(1.0, &stop);
    pacer.wait_for(0.0);
    std::thread stopper([&] {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      stop.store(true);  // as the Ctrl-C handler does: no notification
    });
    const Clock::time_point start = Clock::now();
    EXPECT_FALSE(pacer.wait_for(30.0));
    EXPECT_LT(seconds_since(start), 5.0);
    stopper.join();
  }
}

}  // namespace
}  // namespace ddl::pipeline
