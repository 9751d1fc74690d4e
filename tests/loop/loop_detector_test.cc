// Loop detection's candidates on a synthetic room (steps 1 to 3 of LoopDetector).

#include "ddl/loop/loop_detector.h"

#include <gtest/gtest.h>

#include <algorithm>

#include "synthetic_world.h"

namespace ddl::loop {
namespace {

using test::SyntheticWorld;

// Review finding (stop 14): the database query left out only the keyframes sharing at least 15
// points with the query keyframe (its covisibles). ORB-SLAM2 leaves out every keyframe it shares
// a point with, so that a recent keyframe of the same place, linked through a few points only,
// is no loop.
TEST(LoopDetector, AKeyframeSharingAFewPointsIsNoCandidate) {
  std::mt19937_64 rng(5);
  const SyntheticWorld world = SyntheticWorld::trained_room(3000, rng);
  auto map = std::make_shared<map::Map>();
  auto database = std::make_shared<vocabulary::BowDatabase>();
  // Tracking keeps only the last keyframe's points: the third keyframe sees the first one's
  // place again, but shares with it only the points the second one carried over.
  test::FakeTracker tracker(map, world, /*track_window=*/1);
  auto add = [&](double yaw_deg, double t) {
    const SE3 T_c_w = test::look_along(Vec3d::Zero(), test::rad(yaw_deg));
    const map::KeyFramePtr kf = tracker.make_keyframe(world.observe(T_c_w, rng), T_c_w, t);
    map->add_keyframe(kf);
    for (std::size_t i = 0; i < kf->features().size(); ++i) {
      const map::MapPointPtr& p = kf->map_point(i);
      if (p && !p->is_in(kf->id())) p->add_observation(kf, i, kf->features().has_depth(i));
    }
    kf->update_connections();
    database->add(kf->id(), kf->bow());
    return kf;
  };
  const map::KeyFramePtr place = add(90.0, 0.0);
  add(147.0, 1.0);  // overlaps the place's view by a few degrees, the next one's by more
  const map::KeyFramePtr again = add(100.0, 2.0);

  int shared = 0;
  for (const map::MapPointPtr& p : again->map_points()) shared += (p && p->is_in(place->id()));
  ASSERT_GE(shared, 1) << "the premise: linked through a few points";
  ASSERT_LT(shared, 15) << "the premise: not a covisible";
  ASSERT_EQ(again->weight(place->id()), 0);
  auto has_place = [&](const std::vector<map::KeyFramePtr>& keyframes) {
    return std::any_of(keyframes.begin(), keyframes.end(),
                       [&](const map::KeyFramePtr& kf) { return kf->id() == place->id(); });
  };
  EXPECT_FALSE(has_place(again->covisibles()));
  EXPECT_TRUE(has_place(again->connected_keyframes()));

  LoopDetector detector(LoopDetectionConfig{}, map, database);
  for (const map::KeyFramePtr& kf : detector.candidates(again)) {
    EXPECT_NE(kf->id(), place->id()) << shared << " shared points";
  }
}

}  // namespace
}  // namespace ddl::loop
