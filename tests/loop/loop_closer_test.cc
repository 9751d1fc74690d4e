// Loop closing end to end on a synthetic room: a ring of keyframes whose estimated poses drift
// (injected), built into a map by local mapping as tracking would, returns to its start. The loop
// must be detected, its relative pose estimated within a bound of truth, and after correction
// (pose graph + global BA) every keyframe must be within a bound of truth and far better than
// before. A sequence without revisits (also one with perceptual aliasing) must give no loop; runs
// are deterministic; the background global BA merges or aborts cleanly.

#include "ddl/loop/loop_closer.h"

#include <gtest/gtest.h>

#include <functional>
#include <numeric>
#include <optional>

#include "ddl/loop/loop_verification.h"
#include "ddl/mapping/keyframe_geometry.h"
#include "ddl/mapping/local_mapper.h"
#include "synthetic_world.h"

namespace ddl::loop {
namespace {

using test::SyntheticWorld;

struct RingOptions {
  std::uint64_t seed = 31;
  int keyframes = 32;        // 24 per lap: keyframe 24 is back at the start
  bool drift = true;         // inject accumulating pose drift
  bool aliasing = false;     // copy the start's descriptors onto other walls (shuffled)
  bool stop_at_loop = true;  // stop feeding keyframes once a loop is closed
  bool stop_closer = false;  // stop() the closer at the end instead of waiting for global BA
  LoopCloserConfig loop;
  /// Called where a verified loop is about to be corrected (LoopCloser::on_loop_verified).
  std::function<void(map::Map&)> on_loop_verified;
};

/// A LoopCloser that runs RingOptions::on_loop_verified at its seam.
class HookedLoopCloser final : public LoopCloser {
 public:
  HookedLoopCloser(const LoopCloserConfig& config, const camera::PinholeCamera& camera,
                   std::shared_ptr<map::Map> map,
                   std::shared_ptr<const vocabulary::Vocabulary> vocabulary,
                   std::shared_ptr<vocabulary::BowDatabase> database,
                   std::function<void(map::Map&)> hook)
      : LoopCloser(config, camera, map, std::move(vocabulary), std::move(database)),
        map_(std::move(map)),
        hook_(std::move(hook)) {}

 protected:
  void on_loop_verified(const map::KeyFramePtr& /*keyframe*/, const LoopMatch& /*loop*/) override {
    if (hook_) hook_(*map_);
  }

 private:
  std::shared_ptr<map::Map> map_;
  std::function<void(map::Map&)> hook_;
};

struct RingRun {
  std::shared_ptr<map::Map> map = std::make_shared<map::Map>();
  std::shared_ptr<vocabulary::BowDatabase> database = std::make_shared<vocabulary::BowDatabase>();
  std::map<map::KeyFrameId, SE3> truth;   // true T_c_w per keyframe
  std::map<map::KeyFrameId, SE3> before;  // T_c_w just before the loop correction
  std::vector<LoopResult> results;
  std::optional<LoopResult> loop;
  std::size_t loops_closed = 0;
  std::size_t global_ba_runs = 0;
  std::size_t global_ba_aborted = 0;
  std::size_t loops_deferred = 0;
  int pauses = 0;
  int resumes = 0;
};

SE3 ring_pose(int k) {
  if (k < 24) {
    const double yaw = test::rad(15.0 * k);
    return test::look_along(0.6 * Vec3d(std::sin(yaw), 0.0, std::cos(yaw)), yaw);
  }
  // Second lap: a slightly different circle and heading.
  const double yaw = test::rad(15.0 * k + 2.0);
  return test::look_along(Vec3d(0.65 * std::sin(yaw), 0.05, 0.65 * std::cos(yaw)), yaw);
}

/// Drift of the estimated poses: T_w_c_est = D_k * T_w_c_true with D_k = exp(k * delta), about
/// 3 degrees and 10 cm over a lap.
SE3 drift(int k) {
  const Vec6d delta =
      (Vec6d() << 0.004, 0.0015, -0.0025, test::rad(0.03), test::rad(0.12), test::rad(0.02))
          .finished();
  return SE3::exp(static_cast<double>(k) * delta);
}

double azimuth_deg(const Vec3d& p) {
  double a = test::deg(std::atan2(p.x(), p.z()));
  return a < 0.0 ? a + 360.0 : a;
}

RingRun run_ring(const RingOptions& options) {
  RingRun run;
  std::mt19937_64 rng(options.seed);
  SyntheticWorld world;
  world.points = SyntheticWorld::room(3000, 2.5, 1.5, rng);
  if (options.aliasing) {
    // Walls around azimuth 190..260 degrees get the descriptors of the walls the ring starts at
    // (azimuth -20..50), shuffled: the same words, another geometry.
    std::vector<std::size_t> start;
    std::vector<std::size_t> copy;
    for (std::size_t i = 0; i < world.points.size(); ++i) {
      const double a = azimuth_deg(world.points[i].p_w);
      if (a >= 340.0 || a <= 50.0) start.push_back(i);
      if (a >= 190.0 && a <= 260.0) copy.push_back(i);
    }
    std::shuffle(start.begin(), start.end(), rng);
    for (std::size_t j = 0; j < copy.size(); ++j) {
      world.points[copy[j]].descriptor = world.points[start[j % start.size()]].descriptor;
    }
  }
  world.train_vocabulary(rng);

  mapping::LocalMapperConfig mapping_config;
  mapping_config.bow_levels_up = 2;  // the test vocabulary has 3 levels
  // The synthetic observations are exact projections, so local BA would pull the injected drift
  // back towards the truth anchored by keyframe 0; without it the map keeps the drift, as a
  // drifting tracker's map does.
  mapping_config.local_ba = false;
  mapping::LocalMapper mapper(mapping_config, world.camera, run.map, world.vocabulary,
                              run.database);
  HookedLoopCloser closer(options.loop, world.camera, run.map, world.vocabulary, run.database,
                          options.on_loop_verified);
  closer.set_mapping_pause({[&run] { ++run.pauses; }, [&run] { ++run.resumes; }});
  test::FakeTracker tracker(run.map, world);

  for (int k = 0; k < options.keyframes; ++k) {
    const SE3 T_true = ring_pose(k);
    const SE3 T_est = options.drift ? (drift(k) * T_true.inverse()).inverse() : T_true;
    const test::View view = world.observe(T_true, rng);
    const map::KeyFramePtr kf = tracker.make_keyframe(view, T_est, k);
    run.truth[kf->id()] = T_true;
    const map::KeyFramePtr kept = mapper.process(kf, nullptr);
    if (!kept) continue;
    std::map<map::KeyFrameId, SE3> poses;
    for (const map::KeyFramePtr& other : run.map->keyframes()) poses[other->id()] = other->T_c_w();
    LoopResult result = closer.process(kept);
    run.results.push_back(result);
    if (result.loop_closed && !run.loop) {
      run.loop = result;
      run.before = poses;
      if (options.stop_at_loop) break;
    }
  }
  if (options.stop_closer) {
    closer.stop();
    EXPECT_FALSE(closer.global_ba_running());
  } else {
    closer.wait_for_global_ba();
  }
  run.loops_closed = closer.loops_closed();
  run.global_ba_runs = closer.global_ba_runs();
  run.global_ba_aborted = closer.global_ba_aborted();
  run.loops_deferred = closer.loops_deferred();
  return run;
}

struct Errors {
  double max_center_m = 0.0;
  double mean_center_m = 0.0;
  double max_rotation_deg = 0.0;
};

Errors keyframe_errors(const RingRun& run, bool before) {
  Errors e;
  int n = 0;
  for (const map::KeyFramePtr& kf : run.map->keyframes()) {
    const SE3 T = before ? run.before.at(kf->id()) : kf->T_c_w();
    const double c = test::center_error_m(T, run.truth.at(kf->id()));
    e.max_center_m = std::max(e.max_center_m, c);
    e.mean_center_m += c;
    e.max_rotation_deg =
        std::max(e.max_rotation_deg, test::rotation_error_deg(T, run.truth.at(kf->id())));
    ++n;
  }
  e.mean_center_m /= n;
  return e;
}

/// Relative pose of the matched keyframe in the current camera against truth.
void expect_relative_pose_near_truth(const RingRun& run, double max_m, double max_deg) {
  const SE3 T_true =
      run.truth.at(run.loop->keyframe) * run.truth.at(run.loop->matched_keyframe).inverse();
  const SE3& T_est = run.loop->T_cur_matched;
  EXPECT_LT((T_est.translation() - T_true.translation()).norm(), max_m);
  EXPECT_LT(test::rotation_error_deg(T_est, T_true), max_deg);
}

TEST(LoopCloser, ClosesDriftedRingAndCorrectsPoses) {
  const RingRun run = run_ring({});
  ASSERT_TRUE(run.loop.has_value()) << "no loop closed";
  EXPECT_EQ(run.loops_closed, 1u);
  EXPECT_EQ(run.global_ba_runs, 1u);
  EXPECT_TRUE(run.loop->global_ba_ran);
  // The loop is found at the end of the first lap or the start of the second, against one of the
  // first keyframes.
  EXPECT_GE(run.loop->keyframe, 20u);
  EXPECT_LE(run.loop->matched_keyframe, 6u);
  EXPECT_GE(run.loop->loop_matches, 40);
  // The loop side of the map carries the drift of the keyframes that made its points (about 0.13
  // degrees and 5 mm per keyframe, mixed), so here the estimate is only held to a few keyframes'
  // drift (seeds 1-12 gave 2.1-4.3 cm, 0.38-0.73 deg); RelativePoseMatchesTruthWithoutDrift
  // checks it tightly.
  expect_relative_pose_near_truth(run, 0.06, 1.0);

  const Errors before = keyframe_errors(run, true);
  const Errors after = keyframe_errors(run, false);
  RecordProperty("max_center_error_before_m", std::to_string(before.max_center_m));
  RecordProperty("max_center_error_after_m", std::to_string(after.max_center_m));
  std::printf(
      "keyframe error before correction: centre max %.4f m mean %.4f m, rotation max %.3f deg\n",
      before.max_center_m, before.mean_center_m, before.max_rotation_deg);
  std::printf(
      "keyframe error after correction:  centre max %.4f m mean %.4f m, rotation max %.3f deg\n",
      after.max_center_m, after.mean_center_m, after.max_rotation_deg);
  EXPECT_GT(before.max_center_m, 0.10);  // the drift the loop has to remove
  EXPECT_GT(before.max_rotation_deg, 2.5);
  // What remains is the global BA's estimation error under 0.3 px * scale keypoint noise (about
  // 5 mm / 0.15 degrees on this ring even without any drift: on a wall a small yaw and a sideways
  // shift look alike).
  EXPECT_LT(after.max_center_m, 0.02);
  EXPECT_LT(after.mean_center_m, 0.2 * before.mean_center_m);
  EXPECT_LT(after.max_rotation_deg, 0.5);
}

TEST(LoopCloser, RelativePoseMatchesTruthWithoutDrift) {
  // Without drift the re-observed points still enter the map as new points (tracking lost them
  // in between), so the loop is found; now the relative pose has an exact truth.
  RingOptions options;
  options.drift = false;
  const RingRun run = run_ring(options);
  ASSERT_TRUE(run.loop.has_value());
  // Seeds 1-12: at most 2.6 mm and 0.06 degrees.
  expect_relative_pose_near_truth(run, 0.01, 0.2);
}

TEST(LoopCloser, NoLoopWithoutRevisit) {
  RingOptions options;
  options.keyframes = 18;  // three quarters of a lap: nothing seen twice
  const RingRun run = run_ring(options);
  EXPECT_EQ(run.loops_closed, 0u);
  EXPECT_EQ(run.global_ba_runs, 0u);
}

TEST(LoopCloser, NoLoopFromPerceptualAliasing) {
  // Also with consistency_threshold 0, where every BoW candidate goes to geometric verification.
  for (const int threshold : {3, 0}) {
    RingOptions options;
    options.keyframes = 18;
    options.aliasing = true;
    options.loop.detection.consistency_threshold = threshold;
    const RingRun run = run_ring(options);
    EXPECT_EQ(run.loops_closed, 0u) << "threshold " << threshold;
    // The aliased walls must have produced candidates that geometry then rejected.
    std::size_t verified = 0;
    for (const LoopResult& r : run.results) verified += r.candidates;
    EXPECT_GT(verified, 0u) << "threshold " << threshold;
  }
}

TEST(LoopCloser, ClosesAtOnceWithoutConsistencyRequirement) {
  RingOptions options;
  options.loop.detection.consistency_threshold = 0;
  const RingRun run = run_ring(options);
  ASSERT_TRUE(run.loop.has_value());
  EXPECT_LE(run.loop->matched_keyframe, 6u);
  EXPECT_LT(keyframe_errors(run, false).max_center_m, 0.02);
}

TEST(LoopCloser, DeterministicRuns) {
  const RingRun a = run_ring({});
  const RingRun b = run_ring({});
  ASSERT_TRUE(a.loop && b.loop);
  EXPECT_EQ(a.loop->keyframe, b.loop->keyframe);
  EXPECT_EQ(a.loop->matched_keyframe, b.loop->matched_keyframe);
  EXPECT_EQ(a.loop->loop_matches, b.loop->loop_matches);
  const auto ka = a.map->keyframes();
  const auto kb = b.map->keyframes();
  ASSERT_EQ(ka.size(), kb.size());
  for (std::size_t i = 0; i < ka.size(); ++i) {
    EXPECT_EQ(ka[i]->id(), kb[i]->id());
    EXPECT_EQ(ka[i]->T_c_w().translation(), kb[i]->T_c_w().translation());
    EXPECT_EQ(ka[i]->T_c_w().quaternion().coeffs(), kb[i]->T_c_w().quaternion().coeffs());
  }
  EXPECT_EQ(a.map->map_points().size(), b.map->map_points().size());
}

TEST(LoopCloser, BackgroundGlobalBundleAdjustmentMerges) {
  RingOptions options;
  options.loop.global_ba_in_background = true;
  const RingRun run = run_ring(options);
  ASSERT_TRUE(run.loop.has_value());
  EXPECT_TRUE(run.loop->global_ba_started);
  EXPECT_FALSE(run.loop->global_ba_ran);
  EXPECT_EQ(run.global_ba_runs, 1u);
  EXPECT_EQ(run.global_ba_aborted, 0u);
  // Local mapping was held still for the correction and for the merge.
  EXPECT_EQ(run.pauses, 2);
  EXPECT_EQ(run.resumes, 2);
  EXPECT_LT(keyframe_errors(run, false).max_center_m, 0.02);
}

TEST(LoopCloser, StopAbortsOrFinishesBackgroundGlobalBundleAdjustment) {
  RingOptions options;
  options.loop.global_ba_in_background = true;
  options.stop_closer = true;
  const RingRun run = run_ring(options);
  ASSERT_TRUE(run.loop.has_value());
  // Whether the abort came in time is a race; either way the thread is joined and exactly one
  // outcome is counted, and an aborted result is never merged.
  EXPECT_EQ(run.global_ba_runs + run.global_ba_aborted, 1u);
  EXPECT_EQ(run.pauses, run.global_ba_runs == 1 ? 2 : 1);
  EXPECT_EQ(run.resumes, run.pauses);
}

TEST(LoopCloser, LoopVerifiedAcrossAGlobalBaMergeIsClosedLater) {
  // A background global BA that merges while a loop is verified (simulated at the seam: the
  // merge's big-change notification) leaves the verification with poses from both sides of the
  // merge. The loop must not be corrected with them, but must not be lost either: a later
  // keyframe detects and closes it, and the ring ends up as well corrected as without the race.
  const RingRun reference = run_ring({});
  ASSERT_TRUE(reference.loop.has_value());

  RingOptions options;
  int merges = 0;
  options.on_loop_verified = [&merges](map::Map& map) {
    if (merges++ == 0) map.notify_big_change();
  };
  const RingRun run = run_ring(options);
  EXPECT_EQ(run.loops_deferred, 1u);
  std::size_t deferred_at = 0;
  for (const LoopResult& result : run.results) {
    if (!result.deferred_after_merge) continue;
    EXPECT_FALSE(result.loop_closed);
    deferred_at = result.keyframe;
  }
  EXPECT_EQ(deferred_at, reference.loop->keyframe);  // where the loop was found without the race
  ASSERT_TRUE(run.loop.has_value()) << "the deferred loop was never closed";
  EXPECT_GT(run.loop->keyframe, deferred_at);
  EXPECT_EQ(run.loops_closed, 1u);
  EXPECT_LE(run.loop->matched_keyframe, 6u);
  const Errors before = keyframe_errors(run, true);
  const Errors after = keyframe_errors(run, false);
  EXPECT_GT(before.max_center_m, 0.10);
  EXPECT_LT(after.max_center_m, 0.02);
  EXPECT_LT(after.max_rotation_deg, 0.5);
}

TEST(LoopCloser, TheKeyframeOfAVerifiedLoopStaysProtectedUntilTheCorrection) {
  // Review, stop 25: once a loop was verified the closer released every protected keyframe but
  // the matched one, so local mapping could cull the current keyframe while the correction was
  // about to use it (threaded mode). The hook culls it at that point, as mapping would.
  std::optional<bool> culled;
  RingOptions options;
  options.on_loop_verified = [&culled](map::Map& map) {
    const std::vector<map::KeyFramePtr> keyframes = map.keyframes();
    ASSERT_FALSE(keyframes.empty());
    culled = keyframes.back()->set_bad();  // the newest: the keyframe the loop was found at
  };
  const RingRun run = run_ring(options);
  ASSERT_TRUE(run.loop.has_value());
  ASSERT_TRUE(culled.has_value());
  EXPECT_FALSE(*culled) << "the current keyframe was culled during the loop correction";
  const map::KeyFramePtr current = run.map->keyframe(run.loop->keyframe);
  ASSERT_TRUE(current);
  EXPECT_FALSE(current->is_bad());
  EXPECT_LT(keyframe_errors(run, false).max_center_m, 0.02);
}

TEST(LoopCloser, ANeighbourDoesNotConfirmALoopWithItsOwnPoints) {
  // Review, stop 25: the confirmation in the covisibles projected every loop point, so a
  // neighbour that observes the loop points already matched its own features with them.
  RingOptions options;
  options.keyframes = 18;  // no loop: a plain map to take keyframes from
  const RingRun run = run_ring(options);
  const std::vector<map::KeyFramePtr> keyframes = run.map->keyframes();
  ASSERT_GE(keyframes.size(), 4u);
  const map::KeyFramePtr current = keyframes.back();
  const map::KeyFramePtr neighbour = keyframes[keyframes.size() - 2];
  LoopMatch loop;
  loop.matched = keyframes.front();
  loop.T_cur_w_corrected = current->T_c_w();  // the loop "moves" nothing
  loop.loop_points = neighbour->map_point_set();
  ASSERT_GT(loop.loop_points.size(), 50u);
  const SyntheticWorld world;
  const LoopCloserConfig config;
  EXPECT_EQ(
      confirm_loop_in(neighbour, current, loop, mapping::make_intrinsics(world.camera, config.bf),
                      config.verification, config.optimizer),
      0);
}

TEST(LoopCloser, DisabledDoesNothing) {
  RingOptions options;
  options.loop.enabled = false;
  options.keyframes = 28;
  const RingRun run = run_ring(options);
  EXPECT_EQ(run.loops_closed, 0u);
}

}  // namespace
}  // namespace ddl::loop
