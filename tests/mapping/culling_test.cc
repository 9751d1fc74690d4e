// Recent map point culling and redundant keyframe culling on crafted maps (ORB-SLAM2
// MapPointCulling and KeyFrameCulling).

#include <gtest/gtest.h>

#include "ddl/mapping/keyframe_culling.h"
#include "ddl/mapping/point_culling.h"
#include "synthetic_world.h"

namespace ddl::mapping {
namespace {

/// Features of `n` keypoints at `level`, all with depth `depth_m` (or none when 0).
std::shared_ptr<map::FrameFeatures> crafted_features(std::size_t n, int level, float depth_m) {
  auto f = std::make_shared<map::FrameFeatures>();
  f->pyramid = features::make_scale_pyramid(8, 1.2);
  std::mt19937_64 rng(n * 31 + static_cast<std::size_t>(level));
  std::vector<vocabulary::Descriptor> d;
  for (std::size_t i = 0; i < n; ++i) {
    cv::KeyPoint kp;
    kp.pt = cv::Point2f(20.0f + static_cast<float>(i % 20) * 30.0f,
                        20.0f + static_cast<float>(i / 20) * 30.0f);
    kp.octave = level;
    f->keypoints.push_back(kp);
    f->depth_m.push_back(depth_m);
    f->u_right.push_back(depth_m > 0.0f ? kp.pt.x - static_cast<float>(test::kBf) / depth_m
                                        : -1.0f);
    d.push_back(test::random_descriptor(rng));
  }
  f->descriptors = vocabulary::descriptors_to_mat(d);
  f->grid = features::FeatureGrid(f->keypoints, cv::Rect2f(0.0f, 0.0f, 640.0f, 480.0f));
  return f;
}

map::KeyFramePtr add_keyframe(map::Map& map, std::shared_ptr<map::FrameFeatures> f) {
  auto kf = std::make_shared<map::KeyFrame>(map.next_keyframe_id(), 0.0, std::move(f), SE3());
  map.add_keyframe(kf);
  return kf;
}

map::MapPointPtr add_point(map::Map& map, const map::KeyFramePtr& reference) {
  auto p = std::make_shared<map::MapPoint>(map.next_map_point_id(), Vec3d(0, 0, 2), reference);
  map.add_map_point(p);
  return p;
}

void observe(const map::MapPointPtr& p, const map::KeyFramePtr& kf, std::size_t i) {
  p->add_observation(kf, i, kf->features().has_depth(i));
  kf->set_map_point(i, p);
}

TEST(RecentPoints, CullsPointsObservedTooLittleAfterTwoKeyframes) {
  map::Map map;
  std::vector<map::KeyFramePtr> kfs;
  for (int k = 0; k < 4; ++k) kfs.push_back(add_keyframe(map, crafted_features(10, 0, 2.0f)));
  PointCullingConfig config;
  RecentPoints recent(config);

  const map::MapPointPtr lonely = add_point(map, kfs[1]);  // one stereo observation: 2
  observe(lonely, kfs[1], 0);
  const map::KeyFramePtr mono = add_keyframe(map, crafted_features(10, 0, 0.0f));  // no depth
  const map::MapPointPtr mono_pair = add_point(map, kfs[1]);  // 1 stereo + 1 mono: 3
  observe(mono_pair, kfs[1], 1);
  observe(mono_pair, mono, 1);
  const map::MapPointPtr good = add_point(map, kfs[1]);  // two stereo observations: 4
  observe(good, kfs[1], 2);
  observe(good, kfs[2], 2);
  const map::MapPointPtr unseen = add_point(map, kfs[1]);  // tracking never finds it
  observe(unseen, kfs[1], 3);
  observe(unseen, kfs[2], 3);
  unseen->increase_visible(10);  // found 1 of 11 times
  for (const auto& p : {lonely, mono_pair, good, unseen}) recent.add(p);

  // Keyframe 2 (one keyframe after creation): only the found-ratio rule applies.
  EXPECT_EQ(recent.cull(kfs[2]->id(), map), 1);
  EXPECT_TRUE(unseen->is_bad());
  EXPECT_FALSE(lonely->is_bad());
  EXPECT_EQ(map.map_points().size(), 3u);

  // Keyframe 3 (two after creation): points with <= 3 observations go.
  EXPECT_EQ(recent.cull(kfs[3]->id(), map), 2);
  EXPECT_TRUE(lonely->is_bad());
  EXPECT_TRUE(mono_pair->is_bad());
  EXPECT_FALSE(good->is_bad());
  EXPECT_EQ(recent.size(), 1u);
  EXPECT_FALSE(kfs[1]->map_point(0));  // detached from its keyframe

  // Three keyframes after creation the survivor leaves probation without being culled.
  EXPECT_EQ(recent.cull(kfs[1]->id() + 3, map), 0);
  EXPECT_EQ(recent.size(), 0u);
  EXPECT_FALSE(good->is_bad());
}

/// Five keyframes seeing the same 50 close points (keyframe 3 at `kf3_level`, the others at
/// `level`); keyframe 4 additionally sees `unique` points only keyframe 0 sees too.
struct CullingScene {
  std::shared_ptr<map::Map> map = std::make_shared<map::Map>();
  std::shared_ptr<vocabulary::BowDatabase> database = std::make_shared<vocabulary::BowDatabase>();
  std::vector<map::KeyFramePtr> kfs;
};

CullingScene make_culling_scene(std::size_t unique, int level = 1, int kf3_level = 1,
                                float depth_m = 2.0f, int ids_used_before = 0) {
  CullingScene s;
  // As after a map reset: ids keep counting (Map::clear), the new map's first is not 0.
  for (int i = 0; i < ids_used_before; ++i) s.map->next_keyframe_id();
  for (int k = 0; k < 5; ++k) {
    const std::size_t n = 50 + (k == 0 || k == 4 ? unique : 0);
    s.kfs.push_back(add_keyframe(*s.map, crafted_features(n, k == 3 ? kf3_level : level, depth_m)));
    s.database->add(s.kfs.back()->id(), vocabulary::BowVector::from_entries({{1, 1.0}}));
  }
  for (std::size_t i = 0; i < 50; ++i) {
    const map::MapPointPtr p = add_point(*s.map, s.kfs[0]);
    for (const auto& kf : s.kfs) observe(p, kf, i);
  }
  for (std::size_t i = 50; i < 50 + unique; ++i) {
    const map::MapPointPtr p = add_point(*s.map, s.kfs[4]);
    observe(p, s.kfs[4], i);
    observe(p, s.kfs[0], i);
  }
  for (const auto& kf : s.kfs) kf->update_connections();
  return s;
}

TEST(KeyFrameCulling, KeyframeSeenEverywhereElseIsRedundant) {
  CullingScene s = make_culling_scene(0);
  const KeyFrameCullingConfig config;
  EXPECT_TRUE(is_redundant_keyframe(*s.kfs[2], 3.0, config));
}

TEST(KeyFrameCulling, UniquePointsKeepAKeyframe) {
  // 50 shared + 10 unique: 50/60 = 83 % redundant, not more than 90 %.
  CullingScene s = make_culling_scene(10);
  EXPECT_FALSE(is_redundant_keyframe(*s.kfs[4], 3.0, KeyFrameCullingConfig{}));
  // 50 shared + 4 unique: 93 %.
  CullingScene t = make_culling_scene(4);
  EXPECT_TRUE(is_redundant_keyframe(*t.kfs[4], 3.0, KeyFrameCullingConfig{}));
}

TEST(KeyFrameCulling, ObserversAtCoarserScaleDoNotCount) {
  // Keyframe 3 sees the points at level 0, the others at level 3: for keyframe 3 the others are
  // too coarse (3 > 0 + 1) to make it redundant; for the others every observer counts.
  CullingScene s = make_culling_scene(0, /*level=*/3, /*kf3_level=*/0);
  EXPECT_FALSE(is_redundant_keyframe(*s.kfs[3], 3.0, KeyFrameCullingConfig{}));
  EXPECT_TRUE(is_redundant_keyframe(*s.kfs[2], 3.0, KeyFrameCullingConfig{}));
}

TEST(KeyFrameCulling, FarPointsAreIgnored) {
  // Every point beyond ThDepth: no close point, nothing to judge redundancy by.
  CullingScene s = make_culling_scene(0, 1, 1, /*depth_m=*/5.0f);
  EXPECT_FALSE(is_redundant_keyframe(*s.kfs[2], 3.0, KeyFrameCullingConfig{}));
}

TEST(KeyFrameCulling, CullsRedundantCovisiblesButNeverTheFirstOrProtected) {
  CullingScene s = make_culling_scene(10);
  s.kfs[2]->set_not_erase(true);  // as loop closing does with its candidates
  const std::vector<map::KeyFrameId> culled =
      cull_redundant_keyframes(s.kfs[4], *s.map, *s.database, 3.0, KeyFrameCullingConfig{});
  // Covisibles of keyframe 4: 0 (first, never), 1, 2 (protected), 3. Culling 1 leaves 3 with
  // fewer observers per point (4 -> 3 others), still enough.
  EXPECT_EQ(culled, (std::vector<map::KeyFrameId>{s.kfs[1]->id(), s.kfs[3]->id()}));
  EXPECT_TRUE(s.kfs[1]->is_bad());
  EXPECT_TRUE(s.kfs[3]->is_bad());
  EXPECT_FALSE(s.kfs[0]->is_bad());
  EXPECT_FALSE(s.kfs[2]->is_bad());
  EXPECT_FALSE(s.kfs[4]->is_bad());
  EXPECT_EQ(s.map->keyframe_count(), 3u);
  EXPECT_FALSE(s.database->contains(s.kfs[1]->id()));
  EXPECT_TRUE(s.database->contains(s.kfs[2]->id()));
  // Released by loop closing, the protected keyframe is culled then.
  s.kfs[2]->set_not_erase(false);
  EXPECT_TRUE(s.kfs[2]->is_bad());
}

// Review finding (stop 13): culling and KeyFrame::set_bad tested `id == 0` for the map's first
// keyframe, which after a reset has a higher id; it was culled like any other.
TEST(KeyFrameCulling, NeverCullsTheFirstKeyframeOfAMapMadeAfterAReset) {
  CullingScene s = make_culling_scene(0, 1, 1, 2.0f, /*ids_used_before=*/3);
  ASSERT_EQ(s.kfs[0]->id(), 3u);
  EXPECT_TRUE(s.kfs[0]->is_origin());
  EXPECT_FALSE(s.kfs[1]->is_origin());
  EXPECT_TRUE(is_redundant_keyframe(*s.kfs[0], 3.0, KeyFrameCullingConfig{}));
  cull_redundant_keyframes(s.kfs[4], *s.map, *s.database, 3.0, KeyFrameCullingConfig{});
  EXPECT_FALSE(s.kfs[0]->is_bad());
  EXPECT_FALSE(s.kfs[0]->set_bad());
  EXPECT_TRUE(s.kfs[1]->is_bad());
}

// Review finding (stop 13): a keyframe culled when loop closing released it left the points it
// took below the observation minimum in the map's index.
TEST(KeyFrameCulling, AKeyframeCulledOnReleaseTakesItsOrphanedPointsOutOfTheMap) {
  CullingScene s = make_culling_scene(10);
  const map::MapPointPtr pair_point = add_point(*s.map, s.kfs[2]);
  observe(pair_point, s.kfs[2], 0);
  observe(pair_point, s.kfs[4], 0);
  s.kfs[2]->set_not_erase(true);
  cull_redundant_keyframes(s.kfs[4], *s.map, *s.database, 3.0, KeyFrameCullingConfig{});
  ASSERT_FALSE(s.kfs[2]->is_bad());
  const std::size_t points_before = s.map->map_point_count();
  s.kfs[2]->set_not_erase(false);  // deferred culling happens now
  ASSERT_TRUE(s.kfs[2]->is_bad());
  ASSERT_TRUE(pair_point->is_bad());       // one observer left
  s.map->erase_culled_keyframe(s.kfs[2]);  // what LoopCloser::release does
  EXPECT_EQ(s.map->map_point_count(), points_before - 1);
  EXPECT_EQ(s.map->keyframe(s.kfs[2]->id()), nullptr);
}

// Review finding (stop 25): in threaded mode a fusion can add an observation by a keyframe that
// loop closing is culling on its own thread, after that keyframe erased its observations. Such
// a stale observer must not make other keyframes redundant, and a culled keyframe takes no
// children in the spanning tree.
TEST(KeyFrameCulling, ACulledKeyframeLeftAsObserverDoesNotCount) {
  CullingScene s = make_culling_scene(0);
  cull_redundant_keyframes(s.kfs[4], *s.map, *s.database, 3.0, KeyFrameCullingConfig{});
  ASSERT_TRUE(s.kfs[1]->is_bad());  // 1 and 2 are culled, 3 keeps 0 and 4 as other observers
  ASSERT_TRUE(s.kfs[2]->is_bad());
  ASSERT_FALSE(s.kfs[3]->is_bad());
  ASSERT_FALSE(is_redundant_keyframe(*s.kfs[3], 3.0, KeyFrameCullingConfig{}));
  for (std::size_t i = 0; i < 50; ++i) {
    const map::MapPointPtr p = s.kfs[3]->map_point(i);
    ASSERT_TRUE(p);
    p->add_observation(s.kfs[1], i, true);  // what the race leaves behind
    p->add_observation(s.kfs[2], i, true);
  }
  EXPECT_FALSE(is_redundant_keyframe(*s.kfs[3], 3.0, KeyFrameCullingConfig{}));
  EXPECT_FALSE(s.kfs[1]->add_child(s.kfs[4]));
  EXPECT_TRUE(s.kfs[1]->children().empty());
  EXPECT_TRUE(s.kfs[3]->add_child(s.kfs[4]));
}

TEST(KeyFrameCulling, DisabledCullsNothing) {
  CullingScene s = make_culling_scene(0);
  KeyFrameCullingConfig config;
  config.enabled = false;
  EXPECT_TRUE(cull_redundant_keyframes(s.kfs[4], *s.map, *s.database, 3.0, config).empty());
}

}  // namespace
}  // namespace ddl::mapping
