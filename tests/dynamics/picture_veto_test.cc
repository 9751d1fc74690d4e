#include "ddl/dynamics/picture_veto.h"

#include <gtest/gtest.h>

#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <string>

#include "config_error_check.h"
#include "ddl/camera/pinhole_camera.h"

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

TEST(PictureVeto, ADepthStepWithoutDropoutsStopsTheFloodToo) {
  // The box beside the poster again, now without dropouts between it and the wall: the flood
  // stops at the step by the continuity test alone.
  Room room;
  room.depth_m(cv::Rect(room.poster.br().x + 5, room.poster.y, 80, 200)).setTo(2.2f);
  room.mask(room.poster).setTo(255);
  EXPECT_EQ(cv::countNonZero(drop_pictures(room.mask, room.depth_m, PictureVetoConfig{})), 0);
}

TEST(PictureVeto, TwoRegionsInsideOneCloseBodyAreBothKept) {
  // The second region lies inside the first one's flood: each region floods on its own.
  Room room;
  room.stand(room.body, 1.0f);
  const cv::Rect head(room.body.x + 30, room.body.y + 40, 60, 20);
  const cv::Rect hand(room.body.x + 35, room.body.y + 64, 10, 10);
  room.mask(head).setTo(255);
  room.mask(hand).setTo(255);
  EXPECT_EQ(cv::countNonZero(drop_pictures(room.mask, room.depth_m, PictureVetoConfig{})),
            head.area() + hand.area());
}

TEST(PictureVeto, ReachAndTheContourCountDecide) {
  Room room;
  room.stand(room.body, 1.0f);
  // The torso mask starts 30 px inside the body, whose contour pixels (the first valid ring
  // inside its 2 px dropout band) lie 28 steps from it.
  const cv::Rect torso(room.body.x + 30, room.body.y + 60, 60, 80);
  room.mask(torso).setTo(255);
  PictureVetoConfig config;
  config.reach_px = 27;
  EXPECT_EQ(cv::countNonZero(drop_pictures(room.mask, room.depth_m, config)), 0);
  config.reach_px = 28;
  EXPECT_EQ(cv::countNonZero(drop_pictures(room.mask, room.depth_m, config)), torso.area());
  config.min_near_pixels = 1000000;
  EXPECT_EQ(cv::countNonZero(drop_pictures(room.mask, room.depth_m, config)), 0);
}

TEST(PictureVeto, APersonInFrontOfBackgroundOutOfRangeIsKept) {
  // Nothing behind the person is within the sensor's range: the hole beside the body counts as
  // farther. A dropout band 2 px wide (the body's own) does not.
  Room room;
  room.depth_m.setTo(0.0f);
  room.stand(room.body, 2.0f);
  room.mask(room.body).setTo(255);
  EXPECT_EQ(cv::countNonZero(drop_pictures(room.mask, room.depth_m, PictureVetoConfig{})),
            room.body.area());
}

TEST(PictureVeto, TheBlankMarginOfAnUndistortedFrameIsNoHole) {
  // fr1's calibration: undistortion leaves pixels without a source along the image's edges.
  camera::PinholeCamera fr1;
  fr1.fx = 517.306408;
  fr1.fy = 516.469215;
  fr1.cx = 318.64304;
  fr1.cy = 255.313989;
  fr1.distortion = {0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  const cv::Mat area = camera::Undistorter(fr1).source_area();
  ASSERT_EQ(area.size(), cv::Size(640, 480));
  ASSERT_EQ(area.at<std::uint8_t>(0, 0), 0) << "fr1's corner has no source pixel";
  ASSERT_EQ(area.at<std::uint8_t>(240, 320), 255);
  // The room as the undistorted frame shows it: no depth in the margin.
  Room room;
  room.depth_m.setTo(0.0f, area == 0);
  const cv::Rect corner_poster(16, 16, 120, 90);
  room.mask(corner_poster).setTo(255);
  room.mask(room.body).setTo(255);
  // Without the area the margin reads as a hole beside the poster, as if it stood in front of
  // background out of range: kept.
  EXPECT_EQ(
      cv::countNonZero(drop_pictures(room.mask, room.depth_m, PictureVetoConfig{})(corner_poster)),
      corner_poster.area());
  PictureVetoStats stats;
  const cv::Mat out = drop_pictures(room.mask, room.depth_m, PictureVetoConfig{}, &stats, area);
  EXPECT_EQ(cv::countNonZero(out(corner_poster)), 0);
  EXPECT_EQ(cv::countNonZero(out), room.body.area());
  EXPECT_EQ(stats.dropped, 1);
  // A real hole inside the area still counts: nothing within range behind the person.
  Room far;
  far.depth_m.setTo(0.0f);
  far.stand(far.body, 2.0f);
  far.mask(far.body).setTo(255);
  EXPECT_EQ(
      cv::countNonZero(drop_pictures(far.mask, far.depth_m, PictureVetoConfig{}, nullptr, area)),
      far.body.area());
}

TEST(PictureVeto, RegionsOfInterestGiveTheResultOfTheirCopies) {
  Room room;
  room.mask(room.poster).setTo(255);
  room.mask(room.body).setTo(255);
  // A non-continuous ROI (columns and rows cut out of a wider parent).
  const cv::Rect inner(10, 10, 640, 480);
  cv::Mat mask(500, 700, CV_8UC1, cv::Scalar(255));
  cv::Mat depth(500, 700, CV_32FC1, cv::Scalar(0.0f));
  room.mask.copyTo(mask(inner));
  room.depth_m.copyTo(depth(inner));
  EXPECT_EQ(cv::countNonZero(drop_pictures(mask(inner), depth(inner), PictureVetoConfig{})),
            room.body.area());
  // A continuous ROI (full rows) whose parent holds farther rows just above it: read past the
  // ROI's edge, they would make the top of a poster at the ROI's top a contour.
  Room top;
  const cv::Rect poster(60, 0, 160, 120);
  top.mask(poster).setTo(255);
  cv::Mat parent(520, 640, CV_32FC1, cv::Scalar(9.0f));
  top.depth_m.copyTo(parent.rowRange(40, 520));
  const cv::Mat rows = parent.rowRange(40, 520);
  ASSERT_TRUE(rows.isContinuous());
  EXPECT_EQ(cv::countNonZero(drop_pictures(top.mask, rows, PictureVetoConfig{})), 0);
  EXPECT_EQ(cv::countNonZero(drop_pictures(top.mask, rows.clone(), PictureVetoConfig{})), 0);
}

TEST(PictureVeto, AFloodBudgetKeepsTheRegionsItCannotJudge) {
  Room room;
  room.mask(room.poster).setTo(255);
  PictureVetoConfig config;
  config.max_flood_pixels = 0;
  PictureVetoStats stats;
  EXPECT_EQ(cv::countNonZero(drop_pictures(room.mask, room.depth_m, config, &stats)),
            room.poster.area());
  EXPECT_EQ(stats.unjudged, 1);
  EXPECT_EQ(stats.dropped, 0);
}

TEST(PictureVeto, ConfigErrorsNameTheKey) {
  EXPECT_NO_THROW(PictureVetoConfig{}.validate());
  const auto rejects = [](const char* key, auto&& edit) {
    PictureVetoConfig config;
    edit(config);
    return test_support::throws_config_error_naming([&] { config.validate(); },
                                                    std::string("dynamic.picture_veto.") + key);
  };
  EXPECT_TRUE(rejects("reach_px", [](auto& c) { c.reach_px = -1; }));
  EXPECT_TRUE(rejects("continuity_m", [](auto& c) { c.continuity_m = 0.0; }));
  EXPECT_TRUE(rejects("continuity_quadratic", [](auto& c) { c.continuity_quadratic = -0.1; }));
  EXPECT_TRUE(rejects("contour_window_px", [](auto& c) { c.contour_window_px = 0; }));
  EXPECT_TRUE(rejects("contour_m", [](auto& c) { c.contour_m = 0.0; }));
  EXPECT_TRUE(rejects("contour_quadratic", [](auto& c) { c.contour_quadratic = -0.1; }));
  EXPECT_TRUE(rejects("hole_px", [](auto& c) { c.hole_px = 0; }));
  EXPECT_TRUE(rejects("min_near_pixels", [](auto& c) { c.min_near_pixels = 0; }));
  EXPECT_TRUE(rejects("max_flood_pixels", [](auto& c) { c.max_flood_pixels = -1; }));
}

}  // namespace
}  // namespace ddl::dynamics
