#include "ddl/pipeline/local_mapping_gate.h"

#include <gtest/gtest.h>

#include <chrono>
#include <future>
#include <stdexcept>

namespace ddl::pipeline {
namespace {

using namespace std::chrono_literals;

// How long a call that must block is given to (wrongly) return. A correct gate never returns,
// whatever the machine's load; a wrong one returns at once.
constexpr auto kBlocked = 100ms;
// How long a call that must return is waited for before the test fails.
constexpr auto kReturns = 10s;

// Tracking queues one keyframe, as System::process does.
void queue_keyframe(LocalMappingGate& gate) {
  ASSERT_TRUE(gate.open_insertion());
  gate.close_insertion(/*queued_keyframe=*/true);
}

// The finding of the review: a loop correction must not start while keyframes wait in the
// mapping queue, or they miss the correction.
TEST(LocalMappingGate, APauseWaitsUntilEveryQueuedKeyframeIsProcessed) {
  LocalMappingGate gate;
  queue_keyframe(gate);
  queue_keyframe(gate);
  auto paused = std::async(std::launch::async, [&] { gate.pause(); });
  ASSERT_EQ(paused.wait_for(kBlocked), std::future_status::timeout);
  // The worker may still take both (the stop is requested, not granted), with local BA aborted.
  gate.begin_keyframe();
  EXPECT_TRUE(gate.abort_flag()->load());
  gate.end_keyframe();
  ASSERT_EQ(paused.wait_for(kBlocked), std::future_status::timeout);  // one still queued
  gate.begin_keyframe();
  gate.end_keyframe();
  ASSERT_EQ(paused.wait_for(kReturns), std::future_status::ready);
  gate.resume();
}

// Tracking's "mapping idle": false from the moment a keyframe is queued until the worker has
// processed it, also between the worker taking it off the queue and beginning it.
TEST(LocalMappingGate, MappingIsIdleOnlyWithNoKeyframeQueuedOrInProgress) {
  LocalMappingGate gate;
  EXPECT_TRUE(gate.mapping_idle());
  queue_keyframe(gate);
  EXPECT_FALSE(gate.mapping_idle());  // queued (or taken off the queue, not yet begun)
  gate.begin_keyframe();
  EXPECT_FALSE(gate.mapping_idle());  // in progress
  gate.end_keyframe();
  EXPECT_TRUE(gate.mapping_idle());
  queue_keyframe(gate);
  gate.worker_exited();
  EXPECT_FALSE(gate.mapping_idle());  // nobody will process it
}

// Threaded mode's young map (threaded_lockstep_keyframes): tracking waits until every queued
// keyframe is processed; an exited worker ends the wait.
TEST(LocalMappingGate, WaitingUntilIdleLastsUntilEveryQueuedKeyframeIsProcessed) {
  LocalMappingGate gate;
  gate.wait_until_idle();  // idle: returns at once
  queue_keyframe(gate);
  queue_keyframe(gate);
  auto waited = std::async(std::launch::async, [&] { gate.wait_until_idle(); });
  ASSERT_EQ(waited.wait_for(kBlocked), std::future_status::timeout);
  gate.begin_keyframe();
  gate.end_keyframe();
  ASSERT_EQ(waited.wait_for(kBlocked), std::future_status::timeout);  // one still queued
  gate.begin_keyframe();
  ASSERT_EQ(waited.wait_for(kBlocked), std::future_status::timeout);  // in progress
  gate.end_keyframe();
  ASSERT_EQ(waited.wait_for(kReturns), std::future_status::ready);

  queue_keyframe(gate);
  auto orphaned = std::async(std::launch::async, [&] { gate.wait_until_idle(); });
  ASSERT_EQ(orphaned.wait_for(kBlocked), std::future_status::timeout);
  gate.worker_exited();
  ASSERT_EQ(orphaned.wait_for(kReturns), std::future_status::ready);
}

TEST(LocalMappingGate, TrackingCreatesNoKeyframeWhileAStopIsRequested) {
  LocalMappingGate gate;
  gate.pause();
  EXPECT_FALSE(gate.open_insertion());
  gate.close_insertion(false);
  gate.resume();
  EXPECT_TRUE(gate.open_insertion());
  gate.close_insertion(false);
}

TEST(LocalMappingGate, APauseWaitsForAnOpenInsertion) {
  LocalMappingGate gate;
  ASSERT_TRUE(gate.open_insertion());  // tracking decides on a keyframe
  auto paused = std::async(std::launch::async, [&] { gate.pause(); });
  ASSERT_EQ(paused.wait_for(kBlocked), std::future_status::timeout);
  gate.close_insertion(/*queued_keyframe=*/true);
  // The keyframe tracking queued in the window must be processed before the stop.
  ASSERT_EQ(paused.wait_for(kBlocked), std::future_status::timeout);
  gate.begin_keyframe();
  gate.end_keyframe();
  ASSERT_EQ(paused.wait_for(kReturns), std::future_status::ready);
  gate.resume();
}

TEST(LocalMappingGate, TheWorkerIsHeldWhileMappingIsStopped) {
  LocalMappingGate gate;
  gate.pause();
  auto taken = std::async(std::launch::async, [&] { gate.begin_keyframe(); });
  ASSERT_EQ(taken.wait_for(kBlocked), std::future_status::timeout);
  gate.resume();
  ASSERT_EQ(taken.wait_for(kReturns), std::future_status::ready);
  gate.end_keyframe();
}

TEST(LocalMappingGate, APauseWaitsForTheKeyframeInProgressAndAbortsItsLocalBa) {
  LocalMappingGate gate;
  queue_keyframe(gate);
  gate.begin_keyframe();
  EXPECT_FALSE(gate.abort_flag()->load());  // nothing newer queued
  auto paused = std::async(std::launch::async, [&] { gate.pause(); });
  ASSERT_EQ(paused.wait_for(kBlocked), std::future_status::timeout);
  EXPECT_TRUE(gate.abort_flag()->load());
  gate.end_keyframe();
  ASSERT_EQ(paused.wait_for(kReturns), std::future_status::ready);
  gate.resume();
}

TEST(LocalMappingGate, ANewerKeyframeAbortsTheLocalBaOfTheOlderOne) {
  LocalMappingGate gate;
  queue_keyframe(gate);
  gate.begin_keyframe();
  EXPECT_FALSE(gate.abort_flag()->load());
  queue_keyframe(gate);
  EXPECT_TRUE(gate.abort_flag()->load());
  gate.end_keyframe();
  gate.begin_keyframe();
  EXPECT_FALSE(gate.abort_flag()->load());  // the newest keyframe runs its BA in full
  gate.end_keyframe();
}

// A keyframe the worker took before tracking counted it (push, then pop, then the count) is not
// "newer" than itself.
TEST(LocalMappingGate, AKeyframeTakenBeforeItWasCountedDoesNotAbortItself) {
  LocalMappingGate gate;
  ASSERT_TRUE(gate.open_insertion());
  gate.begin_keyframe();
  gate.close_insertion(/*queued_keyframe=*/true);
  EXPECT_FALSE(gate.abort_flag()->load());
  gate.end_keyframe();
}

TEST(LocalMappingGate, AnExitedWorkerDoesNotBlockAPause) {
  LocalMappingGate gate;
  queue_keyframe(gate);  // never processed: the worker failed
  gate.worker_exited();
  auto paused = std::async(std::launch::async, [&] { gate.pause(); });
  ASSERT_EQ(paused.wait_for(kReturns), std::future_status::ready);
  gate.resume();
}

TEST(LocalMappingGate, AnExceptionCannotLeaveTheInsertionWindowOpen) {
  LocalMappingGate gate;
  try {
    InsertionWindow window(&gate);
    ASSERT_TRUE(window.allowed());
    throw std::runtime_error("tracking failed");
  } catch (const std::runtime_error&) {
  }
  auto paused = std::async(std::launch::async, [&] { gate.pause(); });
  ASSERT_EQ(paused.wait_for(kReturns), std::future_status::ready);
  gate.resume();
}

TEST(LocalMappingGate, PausesNest) {
  LocalMappingGate gate;
  gate.pause();
  gate.pause();
  gate.resume();
  EXPECT_FALSE(gate.open_insertion());  // one stop still held
  gate.close_insertion(false);
  gate.resume();
  EXPECT_TRUE(gate.open_insertion());
  gate.close_insertion(false);
}

// The geometry check's guard: readings taken around a stop, or during one, do not match.
TEST(LocalMappingGate, TheStopSequenceTellsWhetherLoopClosingHeldMappingInBetween) {
  LocalMappingGate gate;
  const std::uint64_t idle = gate.stop_sequence();
  EXPECT_TRUE(LocalMappingGate::unchanged(idle, gate.stop_sequence()));
  gate.pause();
  const std::uint64_t held = gate.stop_sequence();
  EXPECT_FALSE(LocalMappingGate::unchanged(held, held));  // keyframes may be moving now
  gate.pause();                                           // nested: still the same stop
  gate.resume();
  EXPECT_EQ(gate.stop_sequence(), held);
  gate.resume();
  EXPECT_FALSE(LocalMappingGate::unchanged(idle, gate.stop_sequence()));  // a stop came and went
  const std::uint64_t after = gate.stop_sequence();
  EXPECT_TRUE(LocalMappingGate::unchanged(after, gate.stop_sequence()));
}

}  // namespace
}  // namespace ddl::pipeline
