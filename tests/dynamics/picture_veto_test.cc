#include "ddl/dynamics/picture_veto.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "config_error_check.h"

namespace ddl::dynamics {
namespace {

// A wall seen obliquely (2.5 m at the left edge to 3.5 m at the right), a poster painted on it,
// and a person standing at 2 m, with the depth dropouts a Kinect leaves along an occluding
// contour (2 px without depth around the person).
struct Room {
  cv::Mat depth_m{480, 640, CV_32FC1, cv::Scalar(0.0f)};
  cv::Mat mask{480, 640, CV_8UC1, cv::Scalar(0)};
  cv::Rect poster{60, 80, 160, 120};
  cv::Rect body{380, 100, 120, 330};
  Room() {
    for (int v = 0; v < depth_m.rows; ++v) {
      for (int u = 0; u < depth_m.cols; ++u) depth_m.at<float>(v, u) = 2.5f + u / 640.0f;
    }
    stand(body, 2.0f);
  }
  void stand(const cv::Rect& r, float depth) {
    depth_m(r).setTo(0.0f);  // dropouts along the outline, 2 px wide
    depth_m(cv::Rect(r.x + 2, r.y + 2, r.width - 4, r.height - 4)).setTo(depth);
  }
};

TEST(PictureVeto, APosterIsDroppedAndAPersonInFrontOfTheWallKept) {
  Room room;
  room.mask(room.poster).setTo(255);
  room.mask(room.body).setTo(255);
  const cv::Mat before = room.mask.clone();
  PictureVetoStats stats;
  const cv::Mat out = drop_pictures(room.mask, room.depth_m, PictureVetoConfig{}, &stats);
  EXPECT_EQ(cv::norm(room.mask, before, cv::NORM_INF), 0.0) << "the input mask was changed";
  EXPECT_EQ(cv::countNonZero(out(room.poster)), 0);
  EXPECT_EQ(cv::countNonZero(out(room.body)), room.body.area());
  EXPECT_EQ(cv::countNonZero(out), room.body.area());
  EXPECT_EQ(stats.regions, 2);
  EXPECT_EQ(stats.dropped, 1);
  EXPECT_EQ(stats.dropped_px, room.poster.area());
}

TEST(PictureVeto, AMaskInsideACloseBodyReachesTheBodysOutline) {
  // A person close to the camera whose CNN mask covers only the middle of the torso: the mask's
  // own outline shows no contour, the body's outline 30 px away does.
  Room room;
  room.stand(room.body, 1.0f);
  const cv::Rect torso(room.body.x + 30, room.body.y + 60, 60, 80);
  room.mask(torso).setTo(255);
  EXPECT_EQ(cv::countNonZero(drop_pictures(room.mask, room.depth_m, PictureVetoConfig{})),
            torso.area());
  PictureVetoConfig short_reach;
  short_reach.reach_px = 10;
  EXPECT_EQ(cv::countNonZero(drop_pictures(room.mask, room.depth_m, short_reach)), 0);
}

TEST(PictureVeto, ANearerObjectBesideAPictureDoesNotSaveIt) {
  // A box in front of the wall just right of the poster: the flood over the wall meets the box's
  // contour from its far side, which is no sign that the poster stands in front of anything.
  Room room;
  room.stand(cv::Rect(room.poster.br().x + 5, room.poster.y, 80, 200), 2.2f);
  room.mask(room.poster).setTo(255);
  EXPECT_EQ(cv::countNonZero(drop_pictures(room.mask, room.depth_m, PictureVetoConfig{})), 0);
}

TEST(PictureVeto, ARegionWithoutDepthIsKeptAndNothingMaskedGivesNothing) {
  Room room;
  room.depth_m(room.poster).setTo(0.0f);
  room.mask(room.poster).setTo(255);
  EXPECT_EQ(cv::countNonZero(drop_pictures(room.mask, room.depth_m, PictureVetoConfig{})),
            room.poster.area());
  EXPECT_TRUE(drop_pictures(cv::Mat(), room.depth_m, PictureVetoConfig{}).empty());
  PictureVetoStats stats;
  const cv::Mat none(480, 640, CV_8UC1, cv::Scalar(0));
  EXPECT_EQ(cv::countNonZero(drop_pictures(none, room.depth_m, PictureVetoConfig{}, &stats)), 0);
  EXPECT_EQ(stats.regions, 0);
}

TEST(PictureVeto, ConfigErrorsNameTheKey) {
  EXPECT_NO_THROW(PictureVetoConfig{}.validate());
  PictureVetoConfig config;
  config.reach_px = -1;
  EXPECT_TRUE(test_support::throws_config_error_naming([&] { config.validate(); },
                                                       "dynamic.picture_veto.reach_px"));
  config = {};
  config.continuity_m = 0.0;
  EXPECT_TRUE(test_support::throws_config_error_naming([&] { config.validate(); },
                                                       "dynamic.picture_veto.continuity_m"));
  config = {};
  config.min_near_pixels = 0;
  EXPECT_TRUE(test_support::throws_config_error_naming([&] { config.validate(); },
                                                       "dynamic.picture_veto.min_near_pixels"));
}

}  // namespace
}  // namespace ddl::dynamics
