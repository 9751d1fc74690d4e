// Kinect-like depth model: noise level, quantisation, dropouts, determinism.

#include "ddl/synthetic/depth_model.h"

#include <gtest/gtest.h>

#include <cmath>

namespace ddl::synthetic {
namespace {

constexpr double kFactor = 5000.0;

TEST(DepthModel, NoiseFollowsNguyenAndDisparityQuantisation) {
  const DepthNoiseConfig config;
  for (double z : {1.0, 2.0, 3.5}) {
    const cv::Mat depth(200, 200, CV_32FC1, cv::Scalar(z));
    const cv::Mat cos_incidence(200, 200, CV_32FC1, cv::Scalar(1.0));
    const cv::Mat raw = apply_depth_model(depth, cos_incidence, config, kFactor, 7, 0);
    double sum = 0;
    double sum2 = 0;
    int n = 0;
    const double k = config.disparity_fb_px_m * config.disparity_subpixel;
    for (int v = 0; v < raw.rows; ++v) {
      for (int u = 0; u < raw.cols; ++u) {
        const double m = raw.at<std::uint16_t>(v, u) / kFactor;
        ASSERT_GT(m, 0.0);
        // Every value is a disparity level (to the 1/5000 m rounding).
        EXPECT_NEAR(k / std::round(k / m), m, 0.6 / kFactor);
        sum += m - z;
        sum2 += (m - z) * (m - z);
        ++n;
      }
    }
    const double mean = sum / n;
    const double std_dev = std::sqrt(sum2 / n - mean * mean);
    // Expected: Gaussian sigma (Nguyen et al.) combined with the uniform quantisation step.
    const double sigma = 0.0012 + 0.0019 * (z - 0.4) * (z - 0.4);
    const double step = z * z / k;
    const double expected = std::sqrt(sigma * sigma + step * step / 12.0);
    EXPECT_NEAR(std_dev, expected, 0.2 * expected) << "z = " << z;
    EXPECT_LT(std::abs(mean), 0.2 * expected) << "z = " << z;
  }
}

TEST(DepthModel, NoMeasurementOutOfRangeOrAtGrazingAngles) {
  const DepthNoiseConfig config;
  const cv::Mat frontal(20, 20, CV_32FC1, cv::Scalar(1.0));
  for (double z : {0.3, 4.9}) {
    const cv::Mat depth(20, 20, CV_32FC1, cv::Scalar(z));
    EXPECT_EQ(cv::countNonZero(apply_depth_model(depth, frontal, config, kFactor, 1, 0)), 0);
  }
  const cv::Mat depth(20, 20, CV_32FC1, cv::Scalar(2.0));
  const cv::Mat grazing(20, 20, CV_32FC1, cv::Scalar(std::cos(80.0 * M_PI / 180.0)));
  EXPECT_EQ(cv::countNonZero(apply_depth_model(depth, grazing, config, kFactor, 1, 0)), 0);
  const cv::Mat oblique(20, 20, CV_32FC1, cv::Scalar(std::cos(60.0 * M_PI / 180.0)));
  EXPECT_EQ(cv::countNonZero(apply_depth_model(depth, oblique, config, kFactor, 1, 0)), 400);
}

TEST(DepthModel, DepthEdgesLoseTheirFarSide) {
  // A 1.5 m object in front of a 3 m wall: the wall pixels touching the object drop out, the
  // object's own interior and the wall farther away keep their depth.
  const DepthNoiseConfig config;
  cv::Mat depth(60, 60, CV_32FC1, cv::Scalar(3.0));
  depth(cv::Rect(20, 20, 20, 20)).setTo(1.5);
  const cv::Mat cos_incidence(60, 60, CV_32FC1, cv::Scalar(1.0));
  const cv::Mat raw = apply_depth_model(depth, cos_incidence, config, kFactor, 3, 0);
  for (int v = 19; v <= 40; ++v) {
    EXPECT_EQ(raw.at<std::uint16_t>(v, 19), 0) << v;  // wall column left of the object
    EXPECT_EQ(raw.at<std::uint16_t>(v, 40), 0) << v;
  }
  for (int v = 22; v < 38; ++v) {
    for (int u = 22; u < 38; ++u) EXPECT_GT(raw.at<std::uint16_t>(v, u), 0);
  }
  EXPECT_GT(raw.at<std::uint16_t>(5, 5), 0);
  EXPECT_GT(raw.at<std::uint16_t>(50, 50), 0);
}

TEST(DepthModel, MissingDepthTakesTheNearestMeasuredSurface) {
  // A 1 m monitor (left half of the image) with an unmeasured screen, in front of a 3 m wall
  // (right half), and a 2-pixel unmeasured strip on the wall side of their boundary.
  cv::Mat depth(40, 60, CV_32FC1, cv::Scalar(3.0));
  depth(cv::Rect(0, 0, 30, 40)).setTo(1.0);
  depth(cv::Rect(5, 5, 20, 30)).setTo(0.0);  // the screen: nearest measured pixel is the frame
  depth(cv::Rect(30, 0, 2, 40)).setTo(0.0);  // the strip: nearer to the wall column 32 at u = 31
  const cv::Mat filled = fill_missing_depth_nearest(depth);
  for (int v = 5; v < 35; ++v) {
    for (int u = 5; u < 25; ++u) ASSERT_FLOAT_EQ(filled.at<float>(v, u), 1.0f) << u << "," << v;
  }
  // Column 31 is next to the wall (column 32), column 30 next to the monitor (column 29).
  EXPECT_FLOAT_EQ(filled.at<float>(20, 31), 3.0f);
  EXPECT_FLOAT_EQ(filled.at<float>(20, 30), 1.0f);
  EXPECT_FLOAT_EQ(filled.at<float>(0, 59), 3.0f);  // measured pixels are kept
  // Nothing measured at all: unchanged.
  const cv::Mat empty(10, 10, CV_32FC1, cv::Scalar(0.0));
  EXPECT_EQ(cv::countNonZero(fill_missing_depth_nearest(empty)), 0);
}

TEST(DepthModel, DisabledModelOnlyRounds) {
  DepthNoiseConfig config;
  config.enabled = false;
  cv::Mat depth(4, 4, CV_32FC1, cv::Scalar(0));
  depth.at<float>(1, 1) = 1.23456f;
  depth.at<float>(2, 2) = 7.0f;  // beyond the sensor range, kept when the model is off
  const cv::Mat raw =
      apply_depth_model(depth, cv::Mat(4, 4, CV_32FC1, cv::Scalar(1.0)), config, kFactor, 1, 0);
  EXPECT_EQ(raw.at<std::uint16_t>(1, 1), 6173);
  EXPECT_EQ(raw.at<std::uint16_t>(2, 2), 35000);
  EXPECT_EQ(raw.at<std::uint16_t>(0, 0), 0);
}

TEST(DepthModel, NoiseIsAFunctionOfSeedFrameAndPixel) {
  const DepthNoiseConfig config;
  const cv::Mat depth(50, 50, CV_32FC1, cv::Scalar(2.0));
  const cv::Mat cos_incidence(50, 50, CV_32FC1, cv::Scalar(1.0));
  const cv::Mat a = apply_depth_model(depth, cos_incidence, config, kFactor, 9, 4);
  const cv::Mat b = apply_depth_model(depth, cos_incidence, config, kFactor, 9, 4);
  const cv::Mat c = apply_depth_model(depth, cos_incidence, config, kFactor, 9, 5);
  EXPECT_EQ(cv::norm(a, b, cv::NORM_INF), 0.0);
  EXPECT_GT(cv::norm(a, c, cv::NORM_INF), 0.0);
  cv::Mat rgb1(50, 50, CV_8UC3, cv::Scalar(100, 100, 100));
  cv::Mat rgb2 = rgb1.clone();
  cv::Mat mask(50, 50, CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(10, 10, 5, 5)).setTo(255);
  add_rgb_noise(rgb1, 2.0, 9, 4);
  add_rgb_noise(rgb2, 2.0, 9, 4, mask);
  // Masked noise gives the masked pixels exactly the values of the full-image noise.
  EXPECT_EQ(cv::norm(rgb1(cv::Rect(10, 10, 5, 5)), rgb2(cv::Rect(10, 10, 5, 5)), cv::NORM_INF), 0);
  cv::Scalar mean, std_dev;
  cv::meanStdDev(rgb1.reshape(1), mean, std_dev);
  EXPECT_NEAR(std_dev[0], 2.0, 0.3);
}

TEST(DepthModel, ValidateNamesTheKey) {
  DepthNoiseConfig config;
  config.max_range_m = 0.2;
  try {
    config.validate();
    FAIL() << "expected a ConfigError";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("depth.max_range_m"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ddl::synthetic
