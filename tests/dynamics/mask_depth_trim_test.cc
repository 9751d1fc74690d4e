#include "ddl/dynamics/mask_depth_trim.h"

#include <gtest/gtest.h>

#include <opencv2/imgproc.hpp>

#include "config_error_check.h"
#include "ddl/core/error.h"
#include "ddl/dynamics/mask_fusion.h"

namespace ddl::dynamics {
namespace {

// A wall at 3 m with a person (a 120x300 px rectangle) at 2 m, and the person's mask.
struct Scene {
  cv::Mat depth_m{480, 640, CV_32FC1, cv::Scalar(3.0f)};
  cv::Mat person{480, 640, CV_8UC1, cv::Scalar(0)};
  cv::Rect body{260, 100, 120, 300};
  Scene() {
    depth_m(body).setTo(2.0f);
    person(body).setTo(255);
  }
};

TEST(MaskDepthTrim, SpillOntoTheWallBehindIsCutAndThePersonKept) {
  const Scene scene;
  const cv::Mat spilled = feature_exclusion_mask(scene.person, 6);  // the upsampled CNN edge
  const cv::Mat before = spilled.clone();
  const cv::Mat trimmed = trim_mask_by_depth(spilled, scene.depth_m, DepthTrimConfig{});
  EXPECT_EQ(cv::norm(spilled, before, cv::NORM_INF), 0.0) << "the input mask was changed";
  const MaskScore raw = score_mask(spilled, scene.person);
  const MaskScore cut = score_mask(trimmed, scene.person);
  EXPECT_LT(raw.precision, 0.95);
  EXPECT_EQ(cut.recall, 1.0);
  EXPECT_EQ(cut.precision, 1.0);
}

// Non-zero is dynamic: a 0/1 mask is trimmed as its 0/255 copy (the core count divided by 255
// made every rim pixel's reference depth 255 times too deep; review, stop 26).
TEST(MaskDepthTrim, AZeroOneMaskIsTrimmedLikeItsZero255Copy) {
  const Scene scene;
  const cv::Mat spilled = feature_exclusion_mask(scene.person, 6);
  const cv::Mat ones = spilled / 255;
  ASSERT_EQ(cv::countNonZero(ones), cv::countNonZero(spilled));
  const cv::Mat from_255 = trim_mask_by_depth(spilled, scene.depth_m, DepthTrimConfig{});
  const cv::Mat from_ones = trim_mask_by_depth(ones, scene.depth_m, DepthTrimConfig{});
  EXPECT_EQ(cv::countNonZero((from_ones != 0) != (from_255 != 0)), 0);
  EXPECT_LT(cv::countNonZero(from_ones), cv::countNonZero(ones));  // the spill was cut
}

TEST(MaskDepthTrim, NearerPartsAndPixelsWithoutDepthAreKept) {
  Scene scene;
  const cv::Rect arm(200, 200, 60, 20);  // an arm reaching towards the camera
  scene.depth_m(arm).setTo(1.4f);
  scene.person(arm).setTo(255);
  const cv::Rect dropout(300, 150, 10, 10);  // no depth measured inside the body
  scene.depth_m(dropout).setTo(0.0f);
  const cv::Mat trimmed = trim_mask_by_depth(scene.person, scene.depth_m, DepthTrimConfig{});
  EXPECT_EQ(cv::countNonZero(trimmed != scene.person), 0);
}

TEST(MaskDepthTrim, AFartherPersonInTheSameRegionKeepsItsMask) {
  // Two walkers crossing: one at 2 m partly in front of one at 2.8 m, a wall at 3.5 m, and the
  // CNN mask of both, one connected region, spilled onto the wall.
  Scene scene;
  scene.depth_m.setTo(3.5f);
  const cv::Rect far_body(150, 120, 130, 280);
  scene.depth_m(far_body).setTo(2.8f);
  scene.depth_m(scene.body).setTo(2.0f);
  scene.person(far_body).setTo(255);
  const cv::Mat spilled = feature_exclusion_mask(scene.person, 6);
  const cv::Mat trimmed = trim_mask_by_depth(spilled, scene.depth_m, DepthTrimConfig{});
  const MaskScore raw = score_mask(spilled, scene.person);
  const MaskScore cut = score_mask(trimmed, scene.person);
  EXPECT_GT(cut.recall, 0.995);  // at most a few pixels where the two meet
  EXPECT_LT(raw.precision, 0.95);
  EXPECT_GT(cut.precision, 0.99);
}

TEST(MaskDepthTrim, ConfigErrorsNameTheKey) {
  DepthTrimConfig config;
  config.band_m = 0.0;
  EXPECT_TRUE(test_support::throws_config_error_for_key([&] { config.validate(); },
                                                        "dynamic.depth_trim.band_m"));
  EXPECT_NO_THROW(DepthTrimConfig{}.validate());
}

}  // namespace
}  // namespace ddl::dynamics
