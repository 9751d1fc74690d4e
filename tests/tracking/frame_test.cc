#include "ddl/tracking/frame.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "ddl/core/error.h"
#include "ddl/map/map.h"
#include "ddl/tracking/frame_matching.h"
#include "ddl/tracking/keyframe_decision.h"
#include "ddl/tracking/local_map.h"
#include "ddl/tracking/pose_estimation.h"
#include "tracking_test_support.h"

namespace ddl::tracking {
namespace {

using testing::first_room_frame_at_truth;
using testing::room_sequence;
using testing::test_camera;

TEST(FrameTest, ExtractsKeypointsWithExactDepthAndVirtualRight) {
  const TrackerConfig config = testing::test_tracker_config();
  FrameBuilder builder(test_camera(), config.orb, config.frame);
  const io::RgbdFrame& input = room_sequence().frames[0];
  const Frame frame = builder.build(input, cv::Mat(), 0);

  // The textured room fills the image, so the extractor reaches (nearly) its budget.
  ASSERT_GT(frame.size(), 900u);
  EXPECT_LE(frame.size(), 1000u + 8u);
  const map::FrameFeatures& f = frame.features();
  ASSERT_EQ(f.depth_m.size(), frame.size());
  ASSERT_EQ(f.u_right.size(), frame.size());
  EXPECT_EQ(f.grid.size(), frame.size());
  const double bf = config.frame.bf;
  const int r = config.frame.depth_edge_radius_px;
  ASSERT_GT(r, 0);  // the default filter is on
  int with_depth = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const cv::Point2f& pt = f.keypoints[i].pt;
    const int x = static_cast<int>(std::lround(pt.x));
    const int y = static_cast<int>(std::lround(pt.y));
    const float truth = input.depth_m.at<float>(y, x);
    // Every pixel of the room has depth 0.3 .. 4.5 m (inside the valid range): a keypoint gets
    // its pixel's exact depth unless a reading of its window jumps by more than the edge ratio.
    bool at_edge = false;
    for (int yy = std::max(0, y - r); yy <= std::min(input.depth_m.rows - 1, y + r); ++yy) {
      for (int xx = std::max(0, x - r); xx <= std::min(input.depth_m.cols - 1, x + r); ++xx) {
        at_edge |= std::abs(input.depth_m.at<float>(yy, xx) - truth) >
                   config.frame.depth_edge_ratio * truth;
      }
    }
    if (at_edge) {
      ASSERT_EQ(f.depth_m[i], 0.0f) << "keypoint " << i;
      ASSERT_FALSE(frame.has_depth(i));
      continue;
    }
    ASSERT_EQ(f.depth_m[i], truth) << "keypoint " << i;
    ASSERT_FLOAT_EQ(f.u_right[i], pt.x - static_cast<float>(bf) / truth);
    with_depth += frame.has_depth(i) ? 1 : 0;
  }
  // Corners gather on the room's edges, but most lie on its textured surfaces.
  EXPECT_GT(with_depth, static_cast<int>(frame.size()) * 6 / 10);
  EXPECT_LT(with_depth, static_cast<int>(frame.size()));
  EXPECT_NEAR(frame.geometry().close_depth_m, 40.0 * 40.0 / test_camera().fx, 1e-12);
}

TEST(FrameTest, InvalidDepthReadingsAreIgnored) {
  // With the default depth-edge filter: an invalid reading is no edge either ((3, 0), (0, 1)
  // and (3, 3) have them in their windows).
  const FrameGeometry g = FrameGeometry::from(test_camera(), FrameConfig{});
  ASSERT_GT(g.depth_edge_radius_px, 0);
  cv::Mat depth(4, 4, CV_32F, cv::Scalar(2.0f));
  depth.at<float>(1, 1) = 0.0f;
  depth.at<float>(1, 2) = 0.05f;  // below min_depth_m = 0.1
  depth.at<float>(2, 1) = 12.0f;  // above max_depth_m = 10
  depth.at<float>(2, 2) = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(keypoint_depth(depth, 1.2f, 0.8f, g), 0.0f);  // rounds to (1, 1)
  EXPECT_EQ(keypoint_depth(depth, 2.4f, 1.4f, g), 0.0f);
  EXPECT_EQ(keypoint_depth(depth, 1.0f, 2.0f, g), 0.0f);
  EXPECT_EQ(keypoint_depth(depth, 2.0f, 2.0f, g), 0.0f);
  EXPECT_EQ(keypoint_depth(depth, 3.0f, 0.0f, g), 2.0f);
  EXPECT_EQ(keypoint_depth(depth, 0.4f, 1.4f, g), 2.0f);   // rounds to x = 0, y = 1
  EXPECT_EQ(keypoint_depth(depth, -0.6f, 0.0f, g), 0.0f);  // outside
  EXPECT_EQ(keypoint_depth(depth, 3.4f, 3.4f, g), 2.0f);   // rounds to (3, 3)
  EXPECT_EQ(keypoint_depth(depth, 3.6f, 3.0f, g), 0.0f);   // rounds to x = 4: outside
}

TEST(FrameTest, KeypointsNearADepthEdgeGetNoDepthWhenTheFilterIsOn) {
  FrameConfig config;
  config.depth_edge_radius_px = 0;
  const FrameGeometry off = FrameGeometry::from(test_camera(), config);
  config.depth_edge_radius_px = 2;
  config.depth_edge_ratio = 0.1;
  const FrameGeometry on = FrameGeometry::from(test_camera(), config);
  // A person at 1 m in front of a wall at 3 m: columns 0..9 person, 10..19 wall.
  cv::Mat depth(20, 20, CV_32F, cv::Scalar(3.0f));
  depth(cv::Rect(0, 0, 10, 20)).setTo(1.0f);
  depth.at<float>(5, 15) = 3.2f;   // a 6.7% step on the wall: not an edge at ratio 0.1
  depth.at<float>(15, 16) = 0.0f;  // a hole is not an edge
  EXPECT_EQ(keypoint_depth(depth, 9.0f, 10.0f, off), 1.0f);
  EXPECT_EQ(keypoint_depth(depth, 9.0f, 10.0f, on), 0.0f);   // the wall is 1 px away
  EXPECT_EQ(keypoint_depth(depth, 11.0f, 10.0f, on), 0.0f);  // the person is 2 px away
  EXPECT_EQ(keypoint_depth(depth, 12.0f, 10.0f, on), 3.0f);  // 3 px: outside the window
  EXPECT_EQ(keypoint_depth(depth, 7.0f, 10.0f, on), 1.0f);
  EXPECT_EQ(keypoint_depth(depth, 15.0f, 6.0f, on), 3.0f);   // the small step is kept
  EXPECT_EQ(keypoint_depth(depth, 16.0f, 14.0f, on), 3.0f);  // next to the hole
  EXPECT_EQ(keypoint_depth(depth, 0.0f, 0.0f, on), 1.0f);    // the window is clamped to the image
  EXPECT_EQ(keypoint_depth(depth, 19.0f, 19.0f, on), 3.0f);
  config.depth_edge_ratio = 0.05;
  const FrameGeometry strict = FrameGeometry::from(test_camera(), config);
  EXPECT_EQ(keypoint_depth(depth, 15.0f, 6.0f, strict), 0.0f);
}

TEST(FrameTest, DynamicMaskExcludesFeatures) {
  const TrackerConfig config = testing::test_tracker_config();
  FrameBuilder builder(test_camera(), config.orb, config.frame);
  const io::RgbdFrame& input = room_sequence().frames[0];
  cv::Mat mask(input.rgb.size(), CV_8U, cv::Scalar(0));
  const cv::Rect masked(200, 100, 250, 250);
  mask(masked).setTo(255);
  const Frame frame = builder.build(input, mask, 0);
  ASSERT_GT(frame.size(), 800u);  // the budget moves to the rest of the image
  for (const cv::KeyPoint& kp : frame.features().keypoints) {
    const cv::Point p(static_cast<int>(std::lround(kp.pt.x)),
                      static_cast<int>(std::lround(kp.pt.y)));
    EXPECT_EQ(mask.at<std::uint8_t>(p), 0) << "keypoint at " << kp.pt;
  }
}

TEST(FrameTest, DropFeaturesInMaskKeepsTheRestConsistent) {
  const TrackerConfig config = testing::test_tracker_config();
  FrameBuilder builder(test_camera(), config.orb, config.frame);
  const io::RgbdFrame& input = room_sequence().frames[0];
  Frame frame = builder.build(input, cv::Mat(), 0);
  const Frame reference = builder.build(input, cv::Mat(), 0);
  cv::Mat mask(input.rgb.size(), CV_8U, cv::Scalar(0));
  mask(cv::Rect(200, 100, 250, 250)).setTo(255);
  // Mark every slot with a distinct (dummy) map point to follow the slots through the removal.
  std::vector<map::MapPointPtr> points;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    points.push_back(
        std::make_shared<map::MapPoint>(static_cast<map::MapPointId>(i), Vec3d::Zero(), nullptr));
  }
  frame.set_map_points(points);
  frame.set_outlier(0, true);

  std::size_t inside = 0;
  for (const cv::KeyPoint& kp : reference.features().keypoints) {
    inside += mask.at<std::uint8_t>(cv::Point(static_cast<int>(std::lround(kp.pt.x)),
                                              static_cast<int>(std::lround(kp.pt.y)))) != 0;
  }
  ASSERT_GT(inside, 50u);
  EXPECT_EQ(frame.drop_features_in(mask), inside);
  ASSERT_EQ(frame.size(), reference.size() - inside);
  const map::FrameFeatures& f = frame.features();
  ASSERT_EQ(f.descriptors.rows, static_cast<int>(frame.size()));
  ASSERT_EQ(f.depth_m.size(), frame.size());
  ASSERT_EQ(f.u_right.size(), frame.size());
  ASSERT_EQ(f.grid.size(), frame.size());
  for (std::size_t k = 0; k < frame.size(); ++k) {
    // Slot k holds the point made for the original index: its keypoint, descriptor and depth.
    ASSERT_TRUE(frame.map_point(k));
    const auto i = static_cast<std::size_t>(frame.map_point(k)->id());
    const map::FrameFeatures& r = reference.features();
    EXPECT_EQ(f.keypoints[k].pt, r.keypoints[i].pt);
    EXPECT_EQ(cv::norm(f.descriptors.row(static_cast<int>(k)),
                       r.descriptors.row(static_cast<int>(i)), cv::NORM_HAMMING),
              0.0);
    EXPECT_EQ(f.depth_m[k], r.depth_m[i]);
    EXPECT_EQ(f.u_right[k], r.u_right[i]);
    EXPECT_EQ(frame.is_outlier(k), i == 0);
    EXPECT_EQ(mask.at<std::uint8_t>(cv::Point(static_cast<int>(std::lround(f.keypoints[k].pt.x)),
                                              static_cast<int>(std::lround(f.keypoints[k].pt.y)))),
              0);
  }
  // The grid indexes the remaining keypoints.
  const cv::Point2f p = f.keypoints[frame.size() / 2].pt;
  const std::vector<std::size_t> near = f.grid.features_in_area(p.x, p.y, 1.0f);
  EXPECT_NE(std::find(near.begin(), near.end(), frame.size() / 2), near.end());
  EXPECT_EQ(frame.drop_features_in(cv::Mat()), 0u);
  EXPECT_THROW(frame.drop_features_in(cv::Mat(10, 10, CV_8U)), Error);
}

// The mask the extractor checks and the depth and mask a frame reads afterwards are the same
// pixel, also where a coarse level's keypoint lands on a half pixel of level 0 (level 1: rows
// 6m + 2.5; cvRound took row 6m + 2 for the mask, the depth read row 6m + 3).
TEST(FrameTest, ExtractionMaskAndDepthReadTheSamePixel) {
  const TrackerConfig config = testing::test_tracker_config();
  FrameBuilder builder(test_camera(), config.orb, config.frame);
  io::RgbdFrame input = room_sequence().frames[0];
  input.depth_m = input.depth_m.clone();
  cv::Mat mask(input.rgb.size(), CV_8U, cv::Scalar(0));
  constexpr float kMaskedDepth = 0.77f;  // the room is 0.3 .. 4.5 m; no pixel of it is exactly this
  for (int r = 3; r < mask.rows; r += 6) {
    mask.row(r).setTo(255);
    input.depth_m.row(r).setTo(kMaskedDepth);
  }
  Frame frame = builder.build(input, mask, 0);
  ASSERT_GT(frame.size(), 500u);
  int half_pixel_rows = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const float y = frame.features().keypoints[i].pt.y;
    half_pixel_rows += std::fabs(y - std::floor(y) - 0.5f) < 1e-4f ? 1 : 0;
    EXPECT_NE(frame.features().depth_m[i], kMaskedDepth) << "keypoint " << i << " at y " << y;
  }
  ASSERT_GT(half_pixel_rows, 2);  // the case is exercised
  EXPECT_EQ(frame.drop_features_in(mask), 0u);
}

// A point local mapping culled since the last frame takes no slot in the motion-model search:
// it neither displaces the good point matched to the same keypoint nor counts as a match.
TEST(FrameMatcherTest, ACulledPointOfTheLastFrameNeitherTakesASlotNorCounts) {
  auto geometry =
      std::make_shared<FrameGeometry>(FrameGeometry::from(test_camera(), FrameConfig{}));
  constexpr int kOthers = 12;
  cv::RNG rng(1);
  cv::Mat descriptors(kOthers + 1, 32, CV_8U);
  rng.fill(descriptors, cv::RNG::UNIFORM, 0, 256);
  auto features_of = [&](const std::vector<cv::Point2f>& points, const std::vector<float>& angles,
                         const cv::Mat& rows) {
    auto f = std::make_shared<map::FrameFeatures>();
    for (std::size_t i = 0; i < points.size(); ++i) {
      f->keypoints.emplace_back(points[i], 31.0f, angles[i], 50.0f, 0);
    }
    f->descriptors = rows.clone();
    f->pyramid = features::make_scale_pyramid(8, 1.2);
    f->depth_m.assign(points.size(), 0.0f);
    f->u_right.assign(points.size(), -1.0f);
    f->grid = features::FeatureGrid(f->keypoints,
                                    cv::Rect2f(0.0f, 0.0f, static_cast<float>(geometry->width),
                                               static_cast<float>(geometry->height)));
    return f;
  };
  // Current frame: keypoint 0 at the centre, the others on a row, all at orientation 0.
  std::vector<cv::Point2f> current_points{{320.0f, 240.0f}};
  for (int k = 0; k < kOthers; ++k) current_points.emplace_back(60.0f + 40.0f * k, 100.0f);
  // Last frame: the culled point (orientation 180) and a good one (0) on the centre keypoint.
  std::vector<cv::Point2f> last_points{{320.0f, 240.0f}, {320.0f, 240.0f}};
  std::vector<float> last_angles{180.0f, 0.0f};
  cv::Mat last_rows(kOthers + 2, 32, CV_8U);
  descriptors.row(0).copyTo(last_rows.row(0));
  descriptors.row(0).copyTo(last_rows.row(1));
  for (int k = 0; k < kOthers; ++k) {
    last_points.push_back(current_points[static_cast<std::size_t>(k) + 1]);
    last_angles.push_back(0.0f);
    descriptors.row(k + 1).copyTo(last_rows.row(k + 2));
  }
  auto last_features = features_of(last_points, last_angles, last_rows);
  Frame last(1, 0.0, last_features, geometry);
  Frame current(
      2, 0.033,
      features_of(current_points, std::vector<float>(current_points.size(), 0.0f), descriptors),
      geometry);
  last.set_T_c_w(SE3());
  current.set_T_c_w(SE3());
  auto keyframe = std::make_shared<map::KeyFrame>(0, 0.0, last_features, SE3());
  auto point_at = [&](std::size_t i, map::MapPointId id) {
    const cv::Point2f& p = last_points[i];
    const double z = 2.0;
    const Vec3d p_w((p.x - geometry->cx) / geometry->fx * z,
                    (p.y - geometry->cy) / geometry->fy * z, z);
    auto point = std::make_shared<map::MapPoint>(id, p_w, keyframe);
    point->add_observation(keyframe, i, true);
    keyframe->set_map_point(i, point);
    point->compute_distinctive_descriptor();
    point->update_normal_and_depth();
    last.set_map_point(i, point);
    return point;
  };
  const map::MapPointPtr culled = point_at(0, 100);
  const map::MapPointPtr good = point_at(1, 101);
  for (int k = 0; k < kOthers; ++k) point_at(static_cast<std::size_t>(k) + 2, 200 + k);
  culled->set_bad();

  FrameMatcher matcher;
  const int matches = matcher.match_last_frame(current, last, 15.0f);
  EXPECT_EQ(matches, current.matched_count());
  EXPECT_EQ(matches, kOthers + 1);
  EXPECT_EQ(current.map_point(0), good);
}

// The close-point criterion's "established" points are those two keyframes observe; a point
// that one keyframe created from depth is not, although its depth observation counts 2 (the
// weighted count min_observations_for() asks of the reference keyframe's points in a map of
// <= 2 keyframes).
TEST(FrameTest, AClosePointOfOneKeyframeIsNotEstablished) {
  const TrackerConfig config = testing::test_tracker_config();
  FrameBuilder builder(test_camera(), config.orb, config.frame);
  Frame frame = builder.build(room_sequence().frames[0], cv::Mat(), 0);
  std::size_t close = frame.size();
  for (std::size_t i = 0; i < frame.size() && close == frame.size(); ++i) {
    if (frame.is_close(i)) close = i;
  }
  ASSERT_LT(close, frame.size());
  auto first = std::make_shared<map::KeyFrame>(0, 0.0, frame.features_ptr(), SE3());
  auto second = std::make_shared<map::KeyFrame>(1, 0.1, frame.features_ptr(), SE3());
  auto point = std::make_shared<map::MapPoint>(7, frame.unproject_w(close), first);
  point->add_observation(first, close, true);
  frame.set_map_point(close, point);
  EXPECT_EQ(count_close_points(frame).tracked, 1);
  EXPECT_EQ(count_close_points(frame).tracked_established, 0);
  point->add_observation(second, close, true);
  EXPECT_EQ(count_close_points(frame).tracked_established, 1);
}

TEST(FrameTest, RejectsImagesOfTheWrongTypeOrSize) {
  const TrackerConfig config = testing::test_tracker_config();
  FrameBuilder builder(test_camera(), config.orb, config.frame);
  io::RgbdFrame input = room_sequence().frames[0];
  input.depth_path = "depth/0001.png";
  io::RgbdFrame bad_depth = input;
  input.depth_m.convertTo(bad_depth.depth_m, CV_16U);
  try {
    builder.build(bad_depth, cv::Mat(), 0);
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("depth/0001.png"), std::string::npos) << e.what();
  }
  io::RgbdFrame small = input;
  small.rgb = input.rgb(cv::Rect(0, 0, 320, 240)).clone();
  EXPECT_THROW(builder.build(small, cv::Mat(), 0), InputError);
  EXPECT_THROW(builder.build(input, cv::Mat(10, 10, CV_8U), 0), InputError);
}

TEST(FrameTest, UnprojectsKeypointsIntoTheWorld) {
  const TrackerConfig config = testing::test_tracker_config();
  FrameBuilder builder(test_camera(), config.orb, config.frame);
  const auto& seq = room_sequence();
  Frame frame = builder.build(seq.frames[5], cv::Mat(), 5);
  frame.set_T_c_w(seq.T_w_c[5].inverse());
  // A world point from the keypoint's depth projects back onto the keypoint.
  int tested = 0;
  for (std::size_t i = 0; i < frame.size(); i += 7) {
    if (!frame.has_depth(i)) continue;  // next to a depth edge
    ++tested;
    const Vec3d p_c = frame.T_c_w() * frame.unproject_w(i);
    const Vec2d uv = frame.geometry().project(p_c);
    EXPECT_NEAR(uv.x(), frame.features().keypoints[i].pt.x, 1e-4);
    EXPECT_NEAR(uv.y(), frame.features().keypoints[i].pt.y, 1e-4);
    EXPECT_NEAR(p_c.z(), frame.features().depth_m[i], 1e-5);
  }
  EXPECT_GT(tested, 80);
  EXPECT_TRUE((frame.camera_center_w() - seq.T_w_c[5].translation()).norm() < 1e-12);
}

// The local keyframe set of a frame whose points more keyframes observe than the set's bound.
TEST(LocalMapTest, KeyframesObservingTheFramesPointsAllStayBeyondTheBound) {
  const TrackerConfig config = testing::test_tracker_config();
  Frame frame = first_room_frame_at_truth();
  ASSERT_GT(frame.size(), 300u);
  // 120 keyframes (ids 0..119), keyframe k observing the points of keypoints 2k and 2k + 1;
  // the newest, 119, also observes 60 more points: it is the reference.
  std::vector<map::KeyFramePtr> keyframes;
  auto features = std::make_shared<map::FrameFeatures>(frame.features());
  for (int k = 0; k < 120; ++k) {
    keyframes.push_back(std::make_shared<map::KeyFrame>(k, 0.1 * k, features, frame.T_c_w()));
  }
  auto observe = [&](std::size_t i, const map::KeyFramePtr& kf) {
    auto point = std::make_shared<map::MapPoint>(i, frame.unproject_w(i), kf);
    point->add_observation(kf, i, true);
    frame.set_map_point(i, point);
  };
  for (int k = 0; k < 120; ++k) {
    observe(2 * k, keyframes[k]);
    observe(2 * k + 1, keyframes[k]);
  }
  for (std::size_t i = 240; i < 300; ++i) observe(i, keyframes.back());
  MatchingConfig matching = config.matching;
  matching.max_local_keyframes = 80;
  LocalMap local(matching);
  const map::KeyFramePtr reference = local.update(frame);
  ASSERT_EQ(reference, keyframes.back());
  EXPECT_EQ(local.keyframes().size(), 120u);  // K1 is never cut (ORB-SLAM2)
  EXPECT_NE(std::find(local.keyframes().begin(), local.keyframes().end(), reference),
            local.keyframes().end());
}

}  // namespace
}  // namespace ddl::tracking
