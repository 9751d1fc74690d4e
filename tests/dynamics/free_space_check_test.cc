#include "ddl/dynamics/free_space_check.h"

#include <gtest/gtest.h>

#include <limits>
#include <opencv2/imgproc.hpp>

#include "config_error_check.h"
#include "ddl/core/error.h"
#include "ddl/dynamics/mask_fusion.h"
#include "ddl/synthetic/sequence.h"

namespace ddl::dynamics {
namespace {

// Frames of a generated sequence (photos of people when the shared folder is there, else
// procedural silhouettes: the checks hold for both) with their true poses and masks.
class Scene {
 public:
  explicit Scene(const std::string& preset)
      : source_(synthetic::make_sequence_source(synthetic::find_preset(preset).config)) {}

  const camera::PinholeCamera& camera() const { return source_->camera(); }
  synthetic::FrameData frame(std::size_t index) const { return source_->render_frame(index); }
  cv::Mat depth_m(const synthetic::FrameData& f) const {
    cv::Mat depth;
    f.depth_raw.convertTo(depth, CV_32F, 1.0 / camera().depth_factor);
    return depth;
  }
  // Keyframes every `step` frames from `first` up to (not including) `end`, each with its true
  // pose and, when `masked`, its true dynamic mask (what a keyframe's combined mask would be).
  std::vector<FreeSpaceView> views(std::size_t first, std::size_t end, std::size_t step,
                                   bool masked, const FreeSpaceConfig& config) const {
    std::vector<FreeSpaceView> out;
    for (std::size_t k = first; k < end; k += step) {
      const synthetic::FrameData f = frame(k);
      out.push_back(prepare_free_space_view(f.T_w_c, depth_m(f),
                                            masked ? f.dynamic_mask : cv::Mat(), config));
    }
    return out;
  }

 private:
  std::unique_ptr<synthetic::SequenceSource> source_;
};

cv::Mat check(const Scene& scene, const synthetic::FrameData& f,
              const std::vector<FreeSpaceView>& views, const SE3& T_c_w,
              const FreeSpaceConfig& config, FreeSpaceVotes* votes_out = nullptr,
              FreeSpaceStats* stats = nullptr) {
  const cv::Mat depth = scene.depth_m(f);
  const FreeSpaceVotes votes = free_space_votes(depth, T_c_w, views, scene.camera(), config);
  if (votes_out != nullptr) *votes_out = votes;
  const cv::Mat mask = free_space_mask(depth, votes, config, stats);
  return mask.empty() ? cv::Mat::zeros(depth.size(), CV_8UC1) : mask;
}

TEST(FreeSpaceCheck, FindsTheWalkersInSpaceEarlierKeyframesSawEmpty) {
  // syn_walking_rpy frame 400 against 24 keyframes of frames 40-390 at their true poses. The
  // keyframes' own masks cover the people where they were; they still vote free where they saw
  // behind a person's present place.
  const Scene scene("syn_walking_rpy");
  const FreeSpaceConfig config;
  const std::vector<FreeSpaceView> views = scene.views(40, 400, 15, true, config);
  ASSERT_EQ(views.size(), 24u);
  const synthetic::FrameData f = scene.frame(400);
  ASSERT_GT(cv::countNonZero(f.dynamic_mask), 5000);
  FreeSpaceStats stats;
  FreeSpaceConfig ungrown_config = config;
  ungrown_config.grow_step_m = 0.0;  // the free votes' regions alone
  const cv::Mat mask = check(scene, f, views, f.T_w_c.inverse(), ungrown_config, nullptr, &stats);
  const MaskScore s = score_mask(mask, f.dynamic_mask);
  // Measured: IoU 0.84, precision 0.99, recall 0.84.
  EXPECT_GT(s.iou, 0.75) << "precision " << s.precision << " recall " << s.recall;
  EXPECT_GT(s.precision, 0.9);
  EXPECT_GE(stats.regions, 1);
  EXPECT_GT(stats.samples, 10000);
  // Grown over the depth (the default since stop 36): measured IoU 0.82, precision 0.82, recall
  // 0.99; the growth reaches the legs and spreads onto the floor at the bottom border, which no
  // keyframe saw.
  const cv::Mat grown = check(scene, f, views, f.T_w_c.inverse(), config);
  const MaskScore g = score_mask(grown, f.dynamic_mask);
  EXPECT_GT(g.iou, 0.75) << "precision " << g.precision << " recall " << g.recall;
  EXPECT_GT(g.recall, 0.95) << "iou " << g.iou << " precision " << g.precision;
  EXPECT_GT(g.precision, 0.75) << "iou " << g.iou << " recall " << g.recall;
}

TEST(FreeSpaceCheck, AStaticRoomGivesNoMaskEvenWithAPoseError) {
  // syn_static_xyz: the depth noise of the sensor model, and then a pose off by 1 cm and 0.3
  // degrees (more than the low-cost pose is off on the synthetic rooms).
  const Scene scene("syn_static_xyz");
  const FreeSpaceConfig config;
  const std::vector<FreeSpaceView> views = scene.views(0, 360, 15, false, config);
  const synthetic::FrameData f = scene.frame(370);
  const cv::Mat exact = check(scene, f, views, f.T_w_c.inverse(), config);
  EXPECT_EQ(cv::countNonZero(exact), 0);
  Vec6d xi;
  xi << 0.006, -0.006, 0.005, 0.003, -0.0025, 0.002;  // about 1 cm and 0.26 degrees
  const cv::Mat off = check(scene, f, views, SE3::exp(xi) * f.T_w_c.inverse(), config);
  // Measured: 0 pixels.
  EXPECT_LT(cv::countNonZero(off), static_cast<int>(0.002 * off.total()));
}

TEST(FreeSpaceCheck, ARegionTheKeyframesSawAsStaticSurfaceIsDropped) {
  // A CNN-like mask: the true people plus a false region on the room's static background. The
  // votes drop the false region and keep the people.
  const Scene scene("syn_walking_rpy");
  const FreeSpaceConfig config;
  const std::vector<FreeSpaceView> views = scene.views(40, 400, 15, true, config);
  const synthetic::FrameData f = scene.frame(400);
  FreeSpaceVotes votes;
  check(scene, f, views, f.T_w_c.inverse(), config, &votes);
  // The false region: the 120 x 90 window with no person pixel and the most depth.
  const cv::Mat depth = scene.depth_m(f);
  cv::Rect best;
  int most = -1;
  for (int v = 0; v + 90 <= depth.rows; v += 30) {
    for (int u = 0; u + 120 <= depth.cols; u += 30) {
      const cv::Rect r(u, v, 120, 90);
      const cv::Mat grown =
          feature_exclusion_mask(f.dynamic_mask, 10)(r);  // away from the people's rims
      if (cv::countNonZero(grown) > 0) continue;
      const int n = cv::countNonZero(depth(r) > 0.3f);
      if (n > most) most = n, best = r;
    }
  }
  ASSERT_GT(most, 8000);
  cv::Mat mask = f.dynamic_mask.clone();
  mask(best).setTo(255);
  FreeSpaceStats stats;
  const cv::Mat judged = drop_static_regions(mask, votes, config, &stats);
  EXPECT_EQ(cv::countNonZero(judged(best)), 0);
  EXPECT_GE(stats.regions_dropped, 1);
  // Every person region stays (a region of the people is dropped whole or not at all).
  EXPECT_GT(cv::countNonZero(judged & f.dynamic_mask), 0.9 * cv::countNonZero(f.dynamic_mask));
  // Without judging (share 1) nothing is dropped.
  FreeSpaceConfig keep_all = config;
  keep_all.max_static_region_share = 1.0;
  EXPECT_EQ(cv::countNonZero(drop_static_regions(mask, votes, keep_all) != mask), 0);
}

// carve_static_samples: a CNN mask that spills onto the wall around the people (the upsampled
// low-resolution mask) keeps its regions, which are mostly people, but loses the spill's cells
// the keyframes saw as static wall.
TEST(FreeSpaceCheck, CarvingClearsTheSpillOntoTheWallAndKeepsThePeople) {
  const Scene scene("syn_walking_rpy");
  FreeSpaceConfig config;
  const std::vector<FreeSpaceView> views = scene.views(40, 400, 15, true, config);
  const synthetic::FrameData f = scene.frame(400);
  FreeSpaceVotes votes;
  check(scene, f, views, f.T_w_c.inverse(), config, &votes);
  config.carve_static_samples = false;
  const cv::Mat people = f.dynamic_mask != 0;
  cv::Mat spilled;
  cv::dilate(people, spilled, cv::getStructuringElement(cv::MORPH_ELLIPSE, {17, 17}));
  const cv::Mat spill = spilled & ~people & (scene.depth_m(f) > 0.3f);
  const int people_px = cv::countNonZero(people), spill_px = cv::countNonZero(spill);
  ASSERT_GT(spill_px, 3000);
  const cv::Mat kept = drop_static_regions(spilled, votes, config);
  EXPECT_GT(cv::countNonZero(kept & people), 0.95 * people_px) << "the regions are kept";
  EXPECT_GT(cv::countNonZero(kept & spill), 0.9 * spill_px) << "and whole, without carving";
  config.carve_static_samples = true;
  const cv::Mat carved = drop_static_regions(spilled, votes, config);
  EXPECT_GT(cv::countNonZero(carved & people), 0.9 * people_px);  // measured 0.997
  EXPECT_LT(cv::countNonZero(carved & spill), 0.6 * spill_px);    // measured 0.446
}

TEST(FreeSpaceCheck, APersonSittingStillIsKeptWhereKeyframesMaskedThemAsOftenAsNot) {
  // syn_sitting_static: two people seated behind the desk, who barely move. Half the keyframes
  // masked them (a CNN that finds them in one keyframe of two), the other half saw their surface
  // unmasked: a static vote for each masked one. Their regions stay; with every keyframe
  // unmasked, they go.
  const Scene scene("syn_sitting_static");
  const FreeSpaceConfig config;
  std::vector<FreeSpaceView> views = scene.views(100, 460, 15, true, config);
  const std::vector<FreeSpaceView> unmasked = scene.views(100, 460, 15, false, config);
  for (std::size_t k = 1; k < views.size(); k += 2) views[k] = unmasked[k];
  const synthetic::FrameData f = scene.frame(470);
  const int people = cv::countNonZero(f.dynamic_mask);
  ASSERT_GT(people, 5000);
  FreeSpaceVotes votes;
  check(scene, f, views, f.T_w_c.inverse(), config, &votes);
  const cv::Mat judged = drop_static_regions(f.dynamic_mask, votes, config);
  EXPECT_GT(cv::countNonZero(judged), 0.9 * people);
  check(scene, f, unmasked, f.T_w_c.inverse(), config, &votes);
  EXPECT_LT(cv::countNonZero(drop_static_regions(f.dynamic_mask, votes, config)), 0.1 * people);
}

TEST(FreeSpaceCheck, ViewsLookingElsewhereAreNotChosenAndTheChosenSpanThePast) {
  const Scene scene("syn_walking_rpy");
  FreeSpaceConfig config;
  config.max_reference_keyframes = 5;
  const synthetic::FrameData f = scene.frame(400);
  const SE3 T_c_w = f.T_w_c.inverse();
  std::vector<SE3> poses;
  for (std::size_t k = 0; k < 400; k += 20) poses.push_back(scene.frame(k).T_w_c);
  // Two views turned away by 180 degrees about the vertical axis see none of the frame.
  const SE3 turn(Quatd(Eigen::AngleAxisd(M_PI, Vec3d::UnitY())), Vec3d::Zero());
  poses.insert(poses.begin() + 3, f.T_w_c * turn);
  poses.push_back(f.T_w_c * turn);
  const std::vector<std::size_t> chosen =
      select_free_space_views(scene.depth_m(f), T_c_w, poses, scene.camera(), config);
  ASSERT_EQ(chosen.size(), 5u);
  EXPECT_EQ(chosen.front(), 0u);               // the oldest that sees the frame
  EXPECT_EQ(chosen.back(), poses.size() - 2);  // the newest that sees it
  for (const std::size_t k : chosen) {
    EXPECT_NE(k, 3u);
    EXPECT_NE(k, poses.size() - 1);
  }
  EXPECT_TRUE(std::is_sorted(chosen.begin(), chosen.end()));
}

// The packed view (one 16-bit pair per pixel): [0] the window minimum over valid depths in mm,
// [1] the depth rounded to even mm plus the mask bit. Readings of 65 m and beyond are holes (a
// depth of 65.5 m once overflowed into a masked pixel; review, stop 34).
TEST(FreeSpaceCheck, TheViewPacksWindowMinimaDepthsAndTheMaskBit) {
  FreeSpaceConfig config;
  config.window_radius_px = 1;
  config.reference_mask_margin_px = 0;
  cv::Mat depth(5, 8, CV_32FC1, cv::Scalar(2.0f));
  depth.at<float>(1, 1) = 0.0f;     // a hole: not the window's minimum
  depth.at<float>(1, 5) = 1.5f;     // the nearest of its window
  depth.at<float>(3, 3) = 2.0033f;  // rounded to even millimetres
  depth.at<float>(3, 6) = 8.0f;     // beyond max_depth_m (6 m): kept in a view
  depth.at<float>(0, 7) = 70.0f;    // beyond the 16-bit millimetres: a hole
  cv::Mat mask = cv::Mat::zeros(depth.size(), CV_8UC1);
  mask.at<std::uint8_t>(3, 3) = 255;
  const FreeSpaceView view = prepare_free_space_view(SE3(), depth, mask, config);
  ASSERT_EQ(view.packed_mm.type(), CV_16UC2);
  const auto at = [&](int v, int u) { return view.packed_mm.at<cv::Vec<std::uint16_t, 2>>(v, u); };
  EXPECT_EQ(at(1, 1)[0], 2000);  // the hole's window holds valid 2 m depths
  EXPECT_EQ(at(1, 1)[1], 0);     // no depth of its own
  EXPECT_EQ(at(0, 4)[0], 1500);
  EXPECT_EQ(at(2, 6)[0], 1500);
  EXPECT_EQ(at(3, 3)[1], 2004 + 1);  // 2003.3 mm: 1001.65 half-mm rounds to 1002, masked
  EXPECT_EQ(at(3, 2)[1], 2000);      // beside it, unmasked
  EXPECT_EQ(at(3, 6)[1], 8000);
  EXPECT_EQ(at(0, 7)[1], 0);     // no depth
  EXPECT_EQ(at(0, 7)[0], 2000);  // and not part of the window minimum either
}

// Growth over the depth (grow_step_m): a person 1.5 m away in front of a wall 3 m away, whom the
// keyframes saw through only over their upper half (free votes there, no votes below: nobody saw
// behind the legs). The region grows down the person and stops at the depth jump to the wall;
// a floor continuous with the feet stops it where the keyframes saw the floor static, and where
// they did not see the floor at all the growth stays within grow_max_ratio of the region.
struct GrowthScene {
  static constexpr int kStride = 4;
  cv::Mat depth{480, 640, CV_32FC1, cv::Scalar(3.0f)};
  cv::Rect person{200, 100, 120, 240};  // pixels
  FreeSpaceVotes votes;

  GrowthScene() {
    depth(person).setTo(1.5f);
    votes.stride = kStride;
    votes.depth_m = depth;
    const cv::Size lattice(640 / kStride, 480 / kStride);
    votes.free_votes = cv::Mat::zeros(lattice, CV_8UC1);
    votes.static_votes = cv::Mat::zeros(lattice, CV_8UC1);
    votes.masked_votes = cv::Mat::zeros(lattice, CV_8UC1);
    votes.has_depth = cv::Mat::ones(lattice, CV_8UC1);
    votes.static_votes.setTo(3);  // the wall, seen by three keyframes
    const cv::Rect cells = lattice_cells(person);
    votes.static_votes(cells).setTo(0);
    votes.free_votes(cv::Rect(cells.x, cells.y, cells.width, cells.height / 2)).setTo(4);
  }
  // The lattice cells whose samples (at stride * index + stride / 2) lie inside `r`.
  static cv::Rect lattice_cells(const cv::Rect& r) {
    const int x0 = (r.x + kStride / 2) / kStride, y0 = (r.y + kStride / 2) / kStride;
    const int x1 = (r.x + r.width - 1 - kStride / 2) / kStride + 1;
    const int y1 = (r.y + r.height - 1 - kStride / 2) / kStride + 1;
    return {x0, y0, x1 - x0, y1 - y0};
  }
  cv::Mat truth() const {
    cv::Mat t = cv::Mat::zeros(depth.size(), CV_8UC1);
    t(person).setTo(255);
    return t;
  }
};

TEST(FreeSpaceCheck, GrowthOverTheDepthReachesThePartsNoKeyframeSawBehind) {
  GrowthScene scene;
  FreeSpaceConfig config;
  config.grow_step_m = 0.0;
  const cv::Mat ungrown_only = free_space_mask(scene.depth, scene.votes, config);
  const MaskScore before = score_mask(ungrown_only, scene.truth());
  EXPECT_LT(before.recall, 0.6);  // the upper half
  EXPECT_GT(before.precision, 0.99);

  config.grow_step_m = 0.1;
  cv::Mat ungrown;
  const cv::Mat grown = free_space_mask(scene.depth, scene.votes, config, nullptr, &ungrown);
  const MaskScore after = score_mask(grown, scene.truth());
  EXPECT_GT(after.recall, 0.97);
  EXPECT_GT(after.precision, 0.99);  // not onto the wall 1.5 m behind
  // The regions before growth come back unchanged.
  EXPECT_EQ(cv::countNonZero(ungrown != ungrown_only), 0);
}

TEST(FreeSpaceCheck, GrowthStopsOnSurfacesSeenStaticAndIsBoundedOnUnseenOnes) {
  GrowthScene scene;
  // A floor at the person's depth below their feet, continuous with them.
  const cv::Rect floor(0, scene.person.y + scene.person.height, 640,
                       480 - scene.person.y - scene.person.height);
  scene.depth(floor).setTo(1.5f);
  FreeSpaceConfig config;
  config.grow_step_m = 0.1;
  config.grow_max_ratio = 2.0;
  // Seen static by the keyframes: the growth ends at the feet.
  const MaskScore seen =
      score_mask(free_space_mask(scene.depth, scene.votes, config), scene.truth());
  EXPECT_GT(seen.recall, 0.97);
  EXPECT_GT(seen.precision, 0.97);
  // Never seen: it spreads onto the floor, by at most twice the seed region's samples.
  scene.votes.static_votes(GrowthScene::lattice_cells(floor)).setTo(0);
  cv::Mat ungrown;
  const cv::Mat grown = free_space_mask(scene.depth, scene.votes, config, nullptr, &ungrown);
  const int seed_px = cv::countNonZero(ungrown);
  EXPECT_GT(cv::countNonZero(grown), 2 * seed_px);
  EXPECT_LE(cv::countNonZero(grown), 3 * seed_px + 4 * GrowthScene::kStride * 640);
}

// The public functions check what they are given: default votes mean no check ran, votes of
// another image size are an error, not an out-of-bounds read.
TEST(FreeSpaceCheck, VotesOfNoImageOrAnotherImageAreNotRead) {
  const FreeSpaceConfig config;
  const cv::Mat depth(48, 64, CV_32FC1, cv::Scalar(2.0f));
  cv::Mat mask = cv::Mat::zeros(depth.size(), CV_8UC1);
  mask(cv::Rect(10, 10, 20, 20)).setTo(255);
  const FreeSpaceVotes none;
  EXPECT_TRUE(free_space_mask(depth, none, config).empty());
  EXPECT_EQ(cv::countNonZero(drop_static_regions(mask, none, config)), 400);
  const camera::PinholeCamera camera = synthetic::tum3_camera();
  const cv::Mat full(camera.height, camera.width, CV_32FC1, cv::Scalar(2.0f));
  const FreeSpaceVotes other = free_space_votes(
      full, SE3(), {prepare_free_space_view(SE3(), full, cv::Mat(), config)}, camera, config);
  EXPECT_THROW(free_space_mask(depth, other, config), Error);
  EXPECT_THROW(drop_static_regions(mask, other, config), Error);
}

TEST(FreeSpaceCheck, ConfigErrorsNameTheKey) {
  EXPECT_NO_THROW(FreeSpaceConfig{}.validate());
  FreeSpaceConfig config;
  config.max_reference_keyframes = 0;
  EXPECT_TRUE(test_support::throws_config_error_for_key(
      [&] { config.validate(); }, "dynamic.free_space.max_reference_keyframes"));
  config = {};
  config.min_free_votes = config.max_reference_keyframes + 1;
  EXPECT_TRUE(test_support::throws_config_error_for_key([&] { config.validate(); },
                                                        "dynamic.free_space.min_free_votes"));
  config = {};
  config.min_depth_m = 0.0;  // 0 is "no depth"
  EXPECT_TRUE(test_support::throws_config_error_for_key([&] { config.validate(); },
                                                        "dynamic.free_space.min_depth_m"));
  config = {};
  config.min_region_px = std::numeric_limits<int>::max();
  EXPECT_TRUE(test_support::throws_config_error_for_key([&] { config.validate(); },
                                                        "dynamic.free_space.min_region_px"));
  config = {};
  config.max_static_region_share = 1.5;
  EXPECT_TRUE(test_support::throws_config_error_for_key(
      [&] { config.validate(); }, "dynamic.free_space.max_static_region_share"));
  config = {};
  config.grow_step_m = -0.1;
  EXPECT_TRUE(test_support::throws_config_error_for_key([&] { config.validate(); },
                                                        "dynamic.free_space.grow_step_m"));
  config = {};
  config.grow_step_quadratic = std::numeric_limits<double>::quiet_NaN();
  EXPECT_TRUE(test_support::throws_config_error_for_key([&] { config.validate(); },
                                                        "dynamic.free_space.grow_step_quadratic"));
  config = {};
  config.grow_max_ratio = 1e6;
  EXPECT_TRUE(test_support::throws_config_error_for_key([&] { config.validate(); },
                                                        "dynamic.free_space.grow_max_ratio"));
}

}  // namespace
}  // namespace ddl::dynamics
