#include "ddl/segmentation/upright.h"

#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "shared_data.h"

namespace ddl::segmentation {
namespace {
namespace fs = std::filesystem;

using test_support::shared_dir;
constexpr const char* kBasketball = test_support::kBasketballPhoto;
constexpr double kDeg = M_PI / 180.0;

TEST(Upright, TurnMakesUpPointUpTheImage) {
  EXPECT_NEAR(*upright_turn_rad(Vec3d(0, -1, 0)), 0.0, 1e-12);       // upright
  EXPECT_NEAR(*upright_turn_rad(Vec3d(1, 0, 0)), 90 * kDeg, 1e-12);  // up to the image's right
  EXPECT_NEAR(*upright_turn_rad(Vec3d(-1, 0, 0)), -90 * kDeg, 1e-12);
  EXPECT_NEAR(std::abs(*upright_turn_rad(Vec3d(0, 1, 0))), 180 * kDeg, 1e-12);  // upside down
  // Tilted forward or back, the roll is what counts.
  EXPECT_NEAR(*upright_turn_rad(Vec3d(0.3, -0.3, -0.9).normalized()), 45 * kDeg, 1e-12);
  // Looking straight up or down: the image has no up.
  EXPECT_FALSE(upright_turn_rad(Vec3d(0.05, -0.05, 1).normalized()).has_value());
  EXPECT_FALSE(upright_turn_rad(Vec3d(0, 0, -1)).has_value());
}

// Records what it was given; marks the bright pixels dynamic.
class BrightSegmenter final : public Segmenter {
 public:
  SegmentationResult segment(const cv::Mat& bgr, const std::string&) override {
    seen = bgr.clone();
    SegmentationResult result;
    cv::Mat gray;
    cv::cvtColor(bgr, gray, cv::COLOR_BGR2GRAY);
    result.dynamic_mask = gray > 128;
    result.labels = result.dynamic_mask / 255;
    return result;
  }
  std::string description() const override { return "bright"; }
  cv::Mat seen;
};

TEST(Upright, TheNetworkSeesUpAsUpAndTheMaskComesBackInPlace) {
  for (const double roll_deg : {37.0, -70.0, 150.0}) {
    SCOPED_TRACE(roll_deg);
    // Up in the camera, drawn as a bright dot 100 px from the centre in its direction, and a
    // bright square elsewhere.
    const Vec3d up_c(std::sin(roll_deg * kDeg), -std::cos(roll_deg * kDeg), 0.0);
    const cv::Point2d centre(319.5, 239.5);
    cv::Mat bgr(480, 640, CV_8UC3, cv::Scalar::all(0));
    cv::circle(bgr, centre + 100.0 * cv::Point2d(up_c.x(), up_c.y()), 6, cv::Scalar::all(255),
               cv::FILLED);
    const cv::Rect square(380, 250, 60, 50);
    bgr(square).setTo(cv::Scalar::all(255));

    BrightSegmenter segmenter;
    const auto turn = upright_turn_rad(up_c);
    ASSERT_TRUE(turn.has_value());
    EXPECT_NEAR(*turn, roll_deg * kDeg, 1e-9);
    const SegmentationResult result = segment_turned(segmenter, bgr, "frame.png", *turn);

    // The network's input has the dot straight above the centre.
    cv::Mat seen_gray;
    cv::cvtColor(segmenter.seen, seen_gray, cv::COLOR_BGR2GRAY);
    const cv::Moments dot = cv::moments(seen_gray(cv::Rect(300, 120, 40, 40)) > 128, true);
    ASSERT_GT(dot.m00, 50.0);
    EXPECT_NEAR(300 + dot.m10 / dot.m00, centre.x, 1.5);
    EXPECT_NEAR(120 + dot.m01 / dot.m00, centre.y - 100.0, 1.5);

    // The mask is back on the frame's pixels: the square and the dot, nothing else.
    ASSERT_EQ(result.dynamic_mask.size(), bgr.size());
    cv::Mat truth;
    cv::cvtColor(bgr, truth, cv::COLOR_BGR2GRAY);
    truth = truth > 128;
    const double inter = cv::countNonZero(truth & result.dynamic_mask);
    const double uni = cv::countNonZero(truth | result.dynamic_mask);
    EXPECT_GT(inter / uni, 0.9);
    // The labels come back in place too.
    ASSERT_EQ(result.labels.size(), bgr.size());
    const cv::Mat labelled = result.labels > 0;
    EXPECT_GT(cv::countNonZero(truth & labelled) /
                  static_cast<double>(cv::countNonZero(truth | labelled)),
              0.9);
  }
}

// ESPNetv2 does not find the two players of the photo upside down (a camera rolled half a
// turn); turned upright, it finds them where the upright photo has them.
TEST(Upright, TheCnnFindsPeopleInAnUpsideDownFrameOnceTurned) {
  SegmenterConfig config;
  if (!fs::exists(fs::path(shared_dir()) / config.model_path)) GTEST_SKIP() << "no model";
  if (!fs::exists(kBasketball)) GTEST_SKIP() << "opencv-doc not installed: " << kBasketball;
  auto segmenter = make_segmenter(config, shared_dir());
  const cv::Mat upright = cv::imread(kBasketball, cv::IMREAD_COLOR);
  ASSERT_FALSE(upright.empty());
  cv::Mat truth;
  cv::flip(segmenter->segment(upright, kBasketball).dynamic_mask, truth, -1);
  ASSERT_GT(cv::countNonZero(truth), 0.05 * static_cast<double>(truth.total()));

  cv::Mat upside_down;
  cv::flip(upright, upside_down, -1);  // half a turn about the centre
  const auto iou = [&](const cv::Mat& mask) {
    return cv::countNonZero(mask & truth) / static_cast<double>(cv::countNonZero(mask | truth));
  };
  const double plain = iou(segmenter->segment(upside_down, kBasketball).dynamic_mask);
  const auto turn = upright_turn_rad(Vec3d(0, 1, 0));  // up points down the image
  ASSERT_TRUE(turn.has_value());
  const double turned =
      iou(segment_turned(*segmenter, upside_down, kBasketball, *turn).dynamic_mask);
  EXPECT_LT(plain, 0.2);
  EXPECT_GT(turned, 0.9);
}

}  // namespace
}  // namespace ddl::segmentation
