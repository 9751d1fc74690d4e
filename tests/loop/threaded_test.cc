// Local mapping and loop closing on their own threads, joined by bounded queues, with global BA in
// the loop closer's background thread and local mapping paused through the MappingPause hooks —
// the wiring the pipeline's threaded mode uses. The run must close the loop, merge the global BA
// and shut down cleanly.

#include <gtest/gtest.h>

#include <mutex>
#include <thread>

#include "ddl/core/bounded_queue.h"
#include "ddl/loop/loop_closer.h"
#include "ddl/mapping/local_mapper.h"
#include "synthetic_world.h"

namespace ddl::loop {
namespace {

using test::SyntheticWorld;

TEST(ThreadedLoopClosing, MappingAndLoopThreadsWithBackgroundGlobalBundleAdjustment) {
  std::mt19937_64 rng(51);
  SyntheticWorld world;
  world.points = SyntheticWorld::room(3000, 2.5, 1.5, rng);
  world.train_vocabulary(rng);
  auto map = std::make_shared<map::Map>();
  auto database = std::make_shared<vocabulary::BowDatabase>();

  mapping::LocalMapperConfig mapping_config;
  mapping_config.bow_levels_up = 2;
  mapping::LocalMapper mapper(mapping_config, world.camera, map, world.vocabulary, database);
  LoopCloserConfig loop_config;
  loop_config.global_ba_in_background = true;
  LoopCloser closer(loop_config, world.camera, map, world.vocabulary, database);

  // Local mapping holds `mapping_mutex` only while it processes a keyframe (never while it waits
  // on a queue), so pause() returns once the keyframe in progress is done.
  std::mutex mapping_mutex;
  std::atomic<bool> abort_local_ba{false};
  std::atomic<int> pauses{0};
  closer.set_mapping_pause({[&] {
                              abort_local_ba.store(true);
                              mapping_mutex.lock();
                              ++pauses;
                            },
                            [&] { mapping_mutex.unlock(); }});

  BoundedQueue<map::KeyFramePtr> mapping_queue(2);
  BoundedQueue<map::KeyFramePtr> loop_queue(2);
  std::thread mapping_thread([&] {
    while (auto kf = mapping_queue.pop()) {
      map::KeyFramePtr kept;
      {
        std::lock_guard lock(mapping_mutex);
        abort_local_ba.store(false);
        kept = mapper.process(*kf, &abort_local_ba);
      }
      if (kept && !loop_queue.push(kept)) break;
    }
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
    abort_local_ba.store(true);  // a new keyframe interrupts a running local BA
    ASSERT_TRUE(mapping_queue.push(kf));
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
  // Threaded, so not reproducible: 230 local runs (idle, and with 2-4 busy processes beside)
  // gave 0.008-0.018 m; one CI run under `ctest -j2` gave 0.0300 m, a schedule not seen locally.
  EXPECT_LT(max_error, 0.045);
}

}  // namespace
}  // namespace ddl::loop
