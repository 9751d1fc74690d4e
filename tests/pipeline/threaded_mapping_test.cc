// Local mapping and loop closing on their own threads, joined by queues, with global BA in the
// loop closer's background thread and local mapping stopped through LocalMappingGate — the wiring
// of System's threaded mode. The run must close the loop, merge the global BA, correct every
// keyframe (those still queued when the loop is found included) and shut down cleanly.

#include <gtest/gtest.h>

#include <limits>
#include <thread>

#include "ddl/core/bounded_queue.h"
#include "ddl/loop/loop_closer.h"
#include "ddl/mapping/local_mapper.h"
#include "ddl/pipeline/local_mapping_gate.h"
#include "synthetic_world.h"

namespace ddl::pipeline {
namespace {

using test::SyntheticWorld;

using loop::LoopCloser;
using loop::LoopCloserConfig;
using loop::LoopResult;

TEST(ThreadedLoopClosing, MappingAndLoopThreadsWithBackgroundGlobalBundleAdjustment) {
  std::mt19937_64 rng(51);
  const SyntheticWorld world = SyntheticWorld::trained_room(3000, rng);
  auto map = std::make_shared<map::Map>();
  auto database = std::make_shared<vocabulary::BowDatabase>();

  mapping::LocalMapperConfig mapping_config;
  mapping_config.bow_levels_up = 2;
  mapping::LocalMapper mapper(mapping_config, world.camera, map, world.vocabulary, database);
  LoopCloserConfig loop_config;
  loop_config.global_ba_in_background = true;
  LoopCloser closer(loop_config, world.camera, map, world.vocabulary, database);

  LocalMappingGate gate;
  std::atomic<int> pauses{0};
  closer.set_mapping_pause({[&] {
                              gate.pause();
                              ++pauses;
                            },
                            [&] { gate.resume(); }});

  BoundedQueue<map::KeyFramePtr> mapping_queue(2);
  BoundedQueue<map::KeyFramePtr> loop_queue(std::numeric_limits<std::size_t>::max());
  std::thread mapping_thread([&] {
    while (auto kf = mapping_queue.pop()) {
      gate.begin_keyframe();
      const map::KeyFramePtr kept = mapper.process(*kf, gate.abort_flag());
      gate.end_keyframe();
      if (kept && !loop_queue.push(kept)) break;
    }
    gate.worker_exited();
    loop_queue.close();
  });
  std::vector<LoopResult> results;
  std::thread loop_thread([&] {
    while (auto kf = loop_queue.pop()) results.push_back(closer.process(*kf));
  });

  test::FakeTracker tracker(map, world);
  std::map<map::KeyFrameId, SE3> truth;
  for (int k = 0; k < 30; ++k) {
    const double yaw = test::rad(15.0 * k + (k >= 24 ? 2.0 : 0.0));
    const double r = k >= 24 ? 0.65 : 0.6;
    const SE3 T = test::look_along(r * Vec3d(std::sin(yaw), 0.0, std::cos(yaw)), yaw);
    const map::KeyFramePtr kf = tracker.make_keyframe(world.observe(T, rng), T, k);
    truth[kf->id()] = T;
    // The keyframe is made whatever the gate says (the poses are scripted); System would not
    // make one while a stop is requested.
    InsertionWindow insertion(&gate);
    const bool queued = mapping_queue.push(kf);
    insertion.close(queued);
    ASSERT_TRUE(queued);
  }
  mapping_queue.close();
  mapping_thread.join();
  loop_thread.join();
  closer.wait_for_global_ba();
  EXPECT_FALSE(closer.global_ba_running());

  EXPECT_GE(closer.loops_closed(), 1u);
  EXPECT_GE(closer.global_ba_runs() + closer.global_ba_aborted(), closer.loops_closed());
  EXPECT_GE(closer.global_ba_runs(), 1u);
  EXPECT_GE(pauses.load(), 2);
  double max_error = 0.0;
  for (const map::KeyFramePtr& kf : map->keyframes()) {
    max_error = std::max(max_error, test::center_error_m(kf->T_c_w(), truth.at(kf->id())));
  }
  // The loop's correction and the background global BA must leave every keyframe near the truth.
  // Threaded, so not reproducible. With the gate, 130 runs (with a benchmark busy beside them)
  // gave 0.0138-0.0152 m. The wiring before it (the pause waited for the keyframe in progress
  // only) gave about 0.030 m in 11 of 100 runs: keyframes still queued missed the correction.
  EXPECT_LT(max_error, 0.025);
}

}  // namespace
}  // namespace ddl::pipeline
