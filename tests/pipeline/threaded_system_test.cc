// System in threaded mode: local mapping, loop closing and the dense stage on their own threads.
// While the map is young (threaded_lockstep_keyframes), tracking waits before each frame until
// local mapping has processed every queued keyframe; afterwards it does not wait.

#include <gtest/gtest.h>

#include <map>
#include <string>

#include "ddl/pipeline/system.h"
#include "pipeline_test_support.h"

namespace ddl::pipeline {
namespace {

TEST(ThreadedSystem, TrackingWaitsForLocalMappingOnlyWhileTheMapIsYoung) {
  if (!testing::default_vocabulary()) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  constexpr int kFrames = 60;
  const auto source =
      synthetic::make_sequence_source(testing::preset_config("syn_static_rpy", kFrames));
  for (const int lockstep : {0, 4, 1000}) {
    SCOPED_TRACE("threaded_lockstep_keyframes " + std::to_string(lockstep));
    SystemConfig config = testing::core_config();
    config.mode = RunMode::kThreaded;
    config.threaded_lockstep_keyframes = lockstep;
    System system(config, source->camera(), testing::default_vocabulary());
    std::size_t young_frames = 0;  // frames that began with fewer keyframes than `lockstep`
    for (int i = 0; i < kFrames; ++i) {
      if (system.statistics().keyframes_created < static_cast<std::size_t>(lockstep)) {
        ++young_frames;
      }
      system.process(
          testing::to_rgbd(source->render_frame(static_cast<std::size_t>(i)), source->camera()));
    }
    system.finish();
    const std::size_t keyframes = system.statistics().keyframes_created;
    ASSERT_GT(keyframes, 6u) << "the premise: more keyframes than the short lockstep";
    const std::map<std::string, StageSummary> timings = system.timings().summary();
    const auto waits = timings.find("lockstep_wait");
    const std::size_t waited = waits == timings.end() ? 0 : waits->second.count;
    EXPECT_EQ(waited, young_frames);
    if (lockstep == 0) {
      EXPECT_EQ(waited, 0u);
    } else if (lockstep == 4) {
      EXPECT_GT(waited, 0u);
      EXPECT_LT(waited, static_cast<std::size_t>(kFrames));
    } else {
      EXPECT_EQ(waited, static_cast<std::size_t>(kFrames));
    }
  }
}

}  // namespace
}  // namespace ddl::pipeline
