// Global BA split into solve and merge: keyframes and points created while the solve ran follow
// their spanning-tree parent / reference keyframe (ORB-SLAM2 RunGlobalBundleAdjustment).

#include "ddl/loop/global_ba.h"

#include <gtest/gtest.h>

#include "ddl/mapping/local_mapper.h"
#include "synthetic_world.h"

namespace ddl::loop {
namespace {

using test::SyntheticWorld;

TEST(GlobalBundleAdjustment, MergePropagatesToKeyframesAndPointsCreatedMeanwhile) {
  std::mt19937_64 rng(41);
  const SyntheticWorld world = SyntheticWorld::trained_room(2500, rng);
  auto map = std::make_shared<map::Map>();
  auto database = std::make_shared<vocabulary::BowDatabase>();
  mapping::LocalMapperConfig config;
  config.bow_levels_up = 2;
  config.local_ba = false;
  config.keyframe_culling.enabled = false;
  mapping::LocalMapper mapper(config, world.camera, map, world.vocabulary, database);
  test::FakeTracker tracker(map, world);
  auto pose = [](int k) {
    return test::look_along(Vec3d(0.1 * k, 0.0, 0.05 * k), test::rad(4.0 * k));
  };
  // Keyframes 1..4 start 2 cm off, so that the global BA moves them.
  for (int k = 0; k < 5; ++k) {
    SE3 T = pose(k);
    if (k > 0) T = SE3(Quatd::Identity(), Vec3d(0.02, -0.01, 0.01)) * T;
    mapper.process(tracker.make_keyframe(world.observe(pose(k), rng), T, k), nullptr);
  }
  const mapping::CameraIntrinsics camera = mapping::make_intrinsics(world.camera, test::kBf);
  const GlobalBaResult result =
      run_global_bundle_adjustment(*map, camera, optimization::OptimizerConfig{});
  ASSERT_FALSE(result.aborted);
  EXPECT_EQ(result.T_c_w.size(), 5u);

  // Meanwhile tracking and local mapping add keyframe 5 (and its points).
  const map::KeyFramePtr late = tracker.make_keyframe(world.observe(pose(5), rng), pose(5), 5.0);
  mapper.process(late, nullptr);
  ASSERT_EQ(result.T_c_w.count(late->id()), 0u);
  const map::KeyFramePtr parent = late->parent();
  ASSERT_TRUE(parent);
  const SE3 T_late_parent_before = late->T_c_w() * parent->T_w_c();
  map::MapPointPtr late_point;
  for (const map::MapPointPtr& p : late->map_point_set()) {
    if (p->reference_keyframe() == late && result.points_w.count(p->id()) == 0) late_point = p;
  }
  ASSERT_TRUE(late_point);
  const Vec3d late_point_in_camera = late->T_c_w() * late_point->position_w();
  const int big_change = map->big_change_index();

  EXPECT_EQ(merge_global_bundle_adjustment(*map, result), 6u);
  EXPECT_EQ(map->big_change_index(), big_change + 1);
  // Keyframes of the solve take its poses; the late one keeps its pose relative to its parent.
  for (const auto& [id, T] : result.T_c_w) {
    EXPECT_LT((map->keyframe(id)->T_c_w().matrix() - T.matrix()).norm(), 1e-12);
  }
  const SE3 T_late_parent_after = late->T_c_w() * parent->T_w_c();
  EXPECT_LT((T_late_parent_after.matrix() - T_late_parent_before.matrix()).norm(), 1e-9);
  // The late point stays where its reference keyframe saw it.
  EXPECT_LT((late->T_c_w() * late_point->position_w() - late_point_in_camera).norm(), 1e-9);
  // And the solve removed most of the injected 2.4 cm offsets.
  for (int k = 1; k < 5; ++k) {
    EXPECT_LT(
        test::center_error_m(map->keyframe(static_cast<map::KeyFrameId>(k))->T_c_w(), pose(k)),
        0.01);
  }
}

// A reset while a background global BA ran (LoopCloser::request_reset does not wait for it):
// its result must not move the new map nor announce a correction of it.
TEST(GlobalBundleAdjustment, MergeIntoAMapClearedMeanwhileChangesNothing) {
  std::mt19937_64 rng(43);
  const SyntheticWorld world = SyntheticWorld::trained_room(1500, rng);
  auto map = std::make_shared<map::Map>();
  test::FakeTracker tracker(map, world);
  auto pose = [](int k) { return test::look_along(Vec3d(0.1 * k, 0.0, 0.0), test::rad(3.0 * k)); };
  for (int k = 0; k < 3; ++k) {
    map->add_keyframe(tracker.make_keyframe(world.observe(pose(k), rng), pose(k), k));
  }
  const mapping::CameraIntrinsics camera = mapping::make_intrinsics(world.camera, test::kBf);
  GlobalBaResult result =
      run_global_bundle_adjustment(*map, camera, optimization::OptimizerConfig{});
  ASSERT_FALSE(result.aborted);
  ASSERT_EQ(result.T_c_w.size(), 3u);
  // Move the solved poses, so that a merge would show.
  for (auto& [id, T] : result.T_c_w) T = SE3(Quatd::Identity(), Vec3d(0.5, 0.0, 0.0)) * T;

  map->clear();
  std::vector<map::KeyFramePtr> fresh;
  for (int k = 0; k < 2; ++k) {
    fresh.push_back(tracker.make_keyframe(world.observe(pose(k), rng), pose(k), 10.0 + k));
    ASSERT_TRUE(map->add_keyframe(fresh.back()));
  }
  const int big_change = map->big_change_index();
  const std::uint64_t frame_changes = map->frame_change_count();
  EXPECT_EQ(merge_global_bundle_adjustment(*map, result), 0u);
  EXPECT_EQ(map->big_change_index(), big_change);
  EXPECT_EQ(map->frame_change_count(), frame_changes);
  for (int k = 0; k < 2; ++k) {
    EXPECT_LT((fresh[k]->T_c_w().matrix() - pose(k).matrix()).norm(), 1e-12);
  }
}

TEST(GlobalBundleAdjustment, RaisedAbortStopsWithoutResult) {
  std::mt19937_64 rng(42);
  const SyntheticWorld world = SyntheticWorld::trained_room(1500, rng);
  auto map = std::make_shared<map::Map>();
  test::FakeTracker tracker(map, world);
  for (int k = 0; k < 3; ++k) {
    const SE3 T = test::look_along(Vec3d(0.1 * k, 0.0, 0.0), 0.0);
    map::KeyFramePtr kf = tracker.make_keyframe(world.observe(T, rng), T, k);
    map->add_keyframe(kf);
  }
  std::atomic<bool> abort{true};
  const GlobalBaResult result =
      run_global_bundle_adjustment(*map, mapping::make_intrinsics(world.camera, test::kBf),
                                   optimization::OptimizerConfig{}, &abort);
  EXPECT_TRUE(result.aborted);
}

}  // namespace
}  // namespace ddl::loop
