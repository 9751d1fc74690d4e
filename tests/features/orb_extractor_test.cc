#include "ddl/features/orb_extractor.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <numeric>
#include <opencv2/calib3d.hpp>
#include <opencv2/features2d.hpp>
#include <opencv2/imgproc.hpp>

#include "config_error_check.h"
#include "ddl/core/error.h"
#include "ddl/features/matcher.h"
#include "features_test_support.h"

namespace ddl::features {
namespace {

using test::load_tum_rpy_gray;
using test::make_textured_image;

// Cells of a rows x cols grid over the image holding at least one keypoint.
int cells_with_features(const std::vector<cv::KeyPoint>& kps, cv::Size size, int rows = 8,
                        int cols = 10) {
  std::vector<int> hit(rows * cols, 0);
  for (const cv::KeyPoint& kp : kps) {
    const int cx = std::min(cols - 1, static_cast<int>(kp.pt.x * cols / size.width));
    const int cy = std::min(rows - 1, static_cast<int>(kp.pt.y * rows / size.height));
    hit[cy * cols + cx] = 1;
  }
  return std::accumulate(hit.begin(), hit.end(), 0);
}

struct MatchQuality {
  std::size_t matches = 0;
  double within_2px = 0.0;  // fraction of matches within 2 px of the true position
  double within_3px = 0.0;
};

// Brute-force matches a -> b (ratio 0.8, mutual, rotation-consistent) and checks each against the
// known mapping of image a onto image b.
MatchQuality match_against_truth(const OrbFeatures& a, const OrbFeatures& b,
                                 const std::function<cv::Point2f(cv::Point2f)>& a_to_b) {
  const auto matches =
      filter_by_rotation(match_brute_force(a.descriptors, b.descriptors), a.keypoints, b.keypoints);
  MatchQuality q;
  q.matches = matches.size();
  if (matches.empty()) return q;
  int ok2 = 0;
  int ok3 = 0;
  for (const cv::DMatch& m : matches) {
    const double err = cv::norm(a_to_b(a.keypoints[m.queryIdx].pt) - b.keypoints[m.trainIdx].pt);
    ok2 += err <= 2.0;
    ok3 += err <= 3.0;
  }
  q.within_2px = static_cast<double>(ok2) / matches.size();
  q.within_3px = static_cast<double>(ok3) / matches.size();
  return q;
}

void expect_identical(const OrbFeatures& a, const OrbFeatures& b) {
  ASSERT_EQ(a.keypoints.size(), b.keypoints.size());
  for (std::size_t i = 0; i < a.keypoints.size(); ++i) {
    EXPECT_EQ(a.keypoints[i].pt, b.keypoints[i].pt);
    EXPECT_EQ(a.keypoints[i].angle, b.keypoints[i].angle);
    EXPECT_EQ(a.keypoints[i].response, b.keypoints[i].response);
    EXPECT_EQ(a.keypoints[i].octave, b.keypoints[i].octave);
    EXPECT_EQ(a.keypoints[i].size, b.keypoints[i].size);
  }
  ASSERT_EQ(a.descriptors.size(), b.descriptors.size());
  EXPECT_EQ(cv::norm(a.descriptors, b.descriptors, cv::NORM_HAMMING), 0.0);
}

TEST(OrbExtractor, FeaturesPerLevelFollowOrbSlam2sGeometricSeries) {
  // 1000 * (1 - 1/1.2) / (1 - 1.2^-8) = 217.2, then * 1/1.2 per level; the last takes the rest.
  EXPECT_EQ(features_per_level(1000, 8, 1.2),
            (std::vector<int>{217, 181, 151, 126, 105, 87, 73, 60}));
  EXPECT_EQ(features_per_level(50, 1, 1.2), std::vector<int>{50});
  const auto counts = features_per_level(1234, 5, 1.5);
  EXPECT_EQ(std::accumulate(counts.begin(), counts.end(), 0), 1234);
}

TEST(OrbExtractor, ScalePyramidHoldsScalesAndSigmas) {
  const ScalePyramid p = make_scale_pyramid(8, 1.2);
  ASSERT_EQ(p.scale_factors.size(), 8u);
  EXPECT_FLOAT_EQ(p.scale_factors[0], 1.0f);
  EXPECT_FLOAT_EQ(p.scale_factors[3], 1.728f);
  EXPECT_FLOAT_EQ(p.inv_scale_factors[3], 1.0f / 1.728f);
  EXPECT_FLOAT_EQ(p.level_sigma2[2], 1.44f * 1.44f);
  EXPECT_FLOAT_EQ(p.inv_level_sigma2[7], static_cast<float>(std::pow(1.2, -14)));
  EXPECT_DOUBLE_EQ(p.log_scale_factor, std::log(1.2));
}

TEST(OrbExtractor, SyntheticImageGivesTheBudgetSpreadOverTheImage) {
  const cv::Mat image = make_textured_image({640, 480});
  OrbExtractor extractor{OrbExtractorConfig{}};
  const OrbFeatures f = extractor.extract(image);
  EXPECT_GE(f.keypoints.size(), 990u);
  EXPECT_LE(f.keypoints.size(), 1000u + 3u * 8u);  // a quadtree split can overshoot by 3
  EXPECT_GE(cells_with_features(f.keypoints, image.size()), 72);

  ASSERT_EQ(f.descriptors.rows, static_cast<int>(f.keypoints.size()));
  EXPECT_EQ(f.descriptors.cols, kDescriptorBytes);
  EXPECT_EQ(f.descriptors.type(), CV_8UC1);
  EXPECT_EQ(f.pyramid.scale_factors, extractor.scale_pyramid().scale_factors);
  std::vector<int> per_level(8, 0);
  int previous_octave = 0;
  for (const cv::KeyPoint& kp : f.keypoints) {
    ASSERT_GE(kp.octave, 0);
    ASSERT_LT(kp.octave, 8);
    EXPECT_GE(kp.octave, previous_octave) << "keypoints are grouped by level";
    previous_octave = kp.octave;
    ++per_level[kp.octave];
    EXPECT_GE(kp.angle, 0.0f);
    EXPECT_LT(kp.angle, 360.0f);
    EXPECT_GE(kp.response, 7.0f);
    EXPECT_FLOAT_EQ(kp.size, 31.0f * f.pyramid.scale_factors[kp.octave]);
    // At least edge_threshold level pixels from the border, in level-0 pixels.
    const float margin = 19.0f * f.pyramid.scale_factors[kp.octave] - 2.0f;
    EXPECT_GE(kp.pt.x, margin);
    EXPECT_GE(kp.pt.y, margin);
    EXPECT_LE(kp.pt.x, 639.0f - margin);
    EXPECT_LE(kp.pt.y, 479.0f - margin);
  }
  for (int level = 0; level < 8; ++level) {
    EXPECT_GE(per_level[level], extractor.level_targets()[level]) << level;
    EXPECT_LE(per_level[level], extractor.level_targets()[level] + 3) << level;
  }
}

TEST(OrbExtractor, RealFrameGivesTheBudgetSpreadOverTheImage) {
  std::string path;
  const cv::Mat image = load_tum_rpy_gray(0, &path);
  DDL_SKIP_WITHOUT_TUM(image, path);
  OrbExtractor extractor{OrbExtractorConfig{}};
  const OrbFeatures f = extractor.extract(image);
  EXPECT_GE(f.keypoints.size(), 900u);
  EXPECT_LE(f.keypoints.size(), 1024u);
  // Frame 0 has large blank areas (wall, desk top): 57 of the 80 cells get features.
  EXPECT_GE(cells_with_features(f.keypoints, image.size()), 52);
}

TEST(OrbExtractor, MaskedAreaGetsNoKeypointsAndTheBudgetMovesElsewhere) {
  const cv::Mat image = make_textured_image({640, 480}, 3);
  cv::Mat mask(image.size(), CV_8UC1, cv::Scalar(0));
  const cv::Rect masked(160, 120, 320, 240);  // a quarter of the image
  mask(masked).setTo(255);
  OrbExtractor extractor{OrbExtractorConfig{}};
  const OrbFeatures f = extractor.extract(image, mask);
  for (const cv::KeyPoint& kp : f.keypoints) {
    const cv::Point p(cvRound(kp.pt.x), cvRound(kp.pt.y));
    EXPECT_FALSE(masked.contains(p)) << "keypoint at " << kp.pt << " octave " << kp.octave;
  }
  EXPECT_GE(f.keypoints.size(), 950u);
}

TEST(OrbExtractor, MaskedAreaOfARealFrameGetsNoKeypoints) {
  std::string path;
  const cv::Mat real = load_tum_rpy_gray(0, &path);
  DDL_SKIP_WITHOUT_TUM(real, path);
  cv::Mat mask(real.size(), CV_8UC1, cv::Scalar(0));
  const cv::Rect masked(160, 120, 320, 240);
  mask(masked).setTo(255);
  OrbExtractor extractor{OrbExtractorConfig{}};
  const OrbFeatures g = extractor.extract(real, mask);
  int inside = 0;
  for (const cv::KeyPoint& kp : g.keypoints) {
    inside += masked.contains(cv::Point(cvRound(kp.pt.x), cvRound(kp.pt.y)));
  }
  EXPECT_EQ(inside, 0);
  EXPECT_GE(g.keypoints.size(), 850u);
}

// cv::rotate is an exact pixel permutation: (x, y) -> (rows - 1 - y, x).
void check_rotation_by_90(const cv::Mat& image, std::size_t min_matches, double min_within_2px) {
  OrbExtractor extractor{OrbExtractorConfig{}};
  cv::Mat rotated;
  cv::rotate(image, rotated, cv::ROTATE_90_CLOCKWISE);
  const OrbFeatures a = extractor.extract(image);
  const OrbFeatures b = extractor.extract(rotated);
  const float rows = static_cast<float>(image.rows);
  const MatchQuality q = match_against_truth(
      a, b, [rows](cv::Point2f p) { return cv::Point2f(rows - 1.0f - p.y, p.x); });
  EXPECT_GE(q.matches, min_matches);
  EXPECT_GE(q.within_2px, min_within_2px);
}

TEST(OrbExtractor, RotationBy90DegreesKeepsKeypointsAndDescriptors) {
  check_rotation_by_90(make_textured_image({640, 480}), 750, 0.97);  // measured 888, 99.9%
}

TEST(OrbExtractor, RotationBy90DegreesOnARealFrame) {
  std::string path;
  const cv::Mat real = load_tum_rpy_gray(0, &path);
  DDL_SKIP_WITHOUT_TUM(real, path);
  check_rotation_by_90(real, 600, 0.95);  // measured 811, 98.4%
}

TEST(OrbExtractor, RotationBy30DegreesMatchesTheTrueHomography) {
  // Rotate a large textured image about its centre and crop both: every pixel is textured and
  // the true mapping is the rotation.
  const cv::Mat source = make_textured_image({1000, 1000}, 2);
  const cv::Matx23d R = cv::getRotationMatrix2D(cv::Point2f(499.5f, 499.5f), 30.0, 1.0);
  cv::Mat rotated;
  cv::warpAffine(source, rotated, R, source.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
  const cv::Rect crop(180, 260, 640, 480);
  OrbExtractor extractor{OrbExtractorConfig{}};
  const OrbFeatures a = extractor.extract(source(crop).clone());
  const OrbFeatures b = extractor.extract(rotated(crop).clone());
  const MatchQuality q = match_against_truth(a, b, [&](cv::Point2f p) {
    const double x = p.x + crop.x;
    const double y = p.y + crop.y;
    return cv::Point2f(static_cast<float>(R(0, 0) * x + R(0, 1) * y + R(0, 2) - crop.x),
                       static_cast<float>(R(1, 0) * x + R(1, 1) * y + R(1, 2) - crop.y));
  });
  EXPECT_GE(q.matches, 250u);     // measured 382
  EXPECT_GE(q.within_2px, 0.85);  // measured 91.6%
  EXPECT_GE(q.within_3px, 0.92);  // measured 97.9%
}

// 1.5x larger image: pixel centres map as x' + 0.5 = 1.5 (x + 0.5).
void check_scaled_by_1_5(const cv::Mat& image, std::size_t min_matches, double min_within_3px) {
  OrbExtractor extractor{OrbExtractorConfig{}};
  cv::Mat scaled;
  cv::resize(image, scaled, cv::Size(), 1.5, 1.5, cv::INTER_LINEAR);
  const MatchQuality q =
      match_against_truth(extractor.extract(image), extractor.extract(scaled), [](cv::Point2f p) {
        return cv::Point2f((p.x + 0.5f) * 1.5f - 0.5f, (p.y + 0.5f) * 1.5f - 0.5f);
      });
  EXPECT_GE(q.matches, min_matches);
  EXPECT_GE(q.within_3px, min_within_3px);
}

TEST(OrbExtractor, ScaledImageStillMatches) {
  check_scaled_by_1_5(make_textured_image({640, 480}), 250, 0.92);  // measured 340, 97.9%
}

TEST(OrbExtractor, ScaledRealFrameStillMatches) {
  std::string path;
  const cv::Mat real = load_tum_rpy_gray(0, &path);
  DDL_SKIP_WITHOUT_TUM(real, path);
  check_scaled_by_1_5(real, 200, 0.8);  // measured 298, 89.6%
}

TEST(OrbExtractor, ConsecutiveRealFramesGiveManyConsistentMatches) {
  // Brute-force matching (ratio 0.8, mutual, rotation-consistent) of consecutive frames gives
  // 323, 355 and 396 matches here; at least 80% agree with the epipolar geometry that RANSAC
  // finds (2 px): 93%, 92% and 87%.
  OrbExtractor extractor{OrbExtractorConfig{}};
  std::size_t total = 0;
  for (int first : {200, 300, 500}) {
    std::string path;
    const cv::Mat a = load_tum_rpy_gray(first, &path);
    const cv::Mat b = load_tum_rpy_gray(first + 1, &path);
    DDL_SKIP_WITHOUT_TUM(b, path);
    const OrbFeatures fa = extractor.extract(a);
    const OrbFeatures fb = extractor.extract(b);
    const auto matches = filter_by_rotation(match_brute_force(fa.descriptors, fb.descriptors),
                                            fa.keypoints, fb.keypoints);
    EXPECT_GE(matches.size(), 280u) << "frames " << first << ", " << first + 1;
    total += matches.size();
    std::vector<cv::Point2f> pa;
    std::vector<cv::Point2f> pb;
    for (const cv::DMatch& m : matches) {
      pa.push_back(fa.keypoints[m.queryIdx].pt);
      pb.push_back(fb.keypoints[m.trainIdx].pt);
    }
    cv::Mat inliers;
    cv::findFundamentalMat(pa, pb, cv::FM_RANSAC, 2.0, 0.999, inliers);
    EXPECT_GE(cv::countNonZero(inliers), static_cast<int>(0.8 * matches.size()))
        << "frames " << first << ", " << first + 1;
  }
  EXPECT_GE(total, 950u);
}

TEST(OrbExtractor, OutputIsDeterministicWithAnyThreadCount) {
  const cv::Mat image = make_textured_image({640, 480}, 5);
  cv::Mat mask(image.size(), CV_8UC1, cv::Scalar(0));
  cv::circle(mask, {300, 200}, 80, cv::Scalar(255), cv::FILLED);
  OrbExtractor a{OrbExtractorConfig{}};
  const OrbFeatures first = a.extract(image, mask);
  a.extract(make_textured_image({320, 240}, 6));  // different size in between
  expect_identical(first, a.extract(image, mask));
  OrbExtractorConfig two_threads;
  two_threads.num_threads = 2;
  OrbExtractor b{two_threads};
  expect_identical(first, b.extract(image, mask));
}

TEST(OrbExtractor, SmallAndBlankImagesGiveFewOrNoFeatures) {
  OrbExtractor extractor{OrbExtractorConfig{}};
  const OrbFeatures tiny = extractor.extract(make_textured_image({40, 30}));
  EXPECT_TRUE(tiny.keypoints.empty());
  EXPECT_EQ(tiny.descriptors.rows, 0);
  const OrbFeatures small = extractor.extract(make_textured_image({80, 60}));
  EXPECT_EQ(small.descriptors.rows, static_cast<int>(small.keypoints.size()));
  // 80x60 leaves room for keypoints (19 px from the border) on levels 0 and 1 only.
  for (const cv::KeyPoint& kp : small.keypoints) EXPECT_LE(kp.octave, 1);
  const OrbFeatures blank = extractor.extract(cv::Mat(480, 640, CV_8UC1, cv::Scalar(77)));
  EXPECT_TRUE(blank.keypoints.empty());
}

TEST(OrbExtractor, WrongImageOrMaskIsAnInputError) {
  OrbExtractor extractor{OrbExtractorConfig{}};
  const cv::Mat gray = make_textured_image({320, 240});
  EXPECT_THROW(extractor.extract(cv::Mat()), InputError);
  EXPECT_THROW(extractor.extract(cv::Mat(240, 320, CV_8UC3, cv::Scalar::all(0))), InputError);
  EXPECT_THROW(extractor.extract(gray, cv::Mat(100, 100, CV_8UC1, cv::Scalar(0))), InputError);
  EXPECT_THROW(extractor.extract(gray, cv::Mat(240, 320, CV_32FC1, cv::Scalar(0))), InputError);
  try {
    extractor.extract(cv::Mat(240, 320, CV_16UC1, cv::Scalar(0)));
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("CV_8UC1"), std::string::npos) << e.what();
  }
}

TEST(OrbExtractor, ConfigValidationNamesTheKey) {
  const std::vector<std::pair<std::function<void(OrbExtractorConfig&)>, std::string>> cases = {
      {[](auto& c) { c.num_features = 0; }, "orb.num_features"},
      {[](auto& c) { c.scale_factor = 1.0; }, "orb.scale_factor"},
      {[](auto& c) { c.num_levels = 0; }, "orb.num_levels"},
      {[](auto& c) { c.fast_threshold_initial = 0; }, "orb.fast_threshold_initial"},
      {[](auto& c) { c.fast_threshold_min = 30; }, "orb.fast_threshold_min"},
      {[](auto& c) { c.patch_size = 30; }, "orb.patch_size"},
      {[](auto& c) { c.edge_threshold = 10; }, "orb.edge_threshold"},
      {[](auto& c) { c.cell_size_px = 2; }, "orb.cell_size_px"},
      {[](auto& c) { c.num_threads = 0; }, "orb.num_threads"},
  };
  for (const auto& [mutate, key] : cases) {
    OrbExtractorConfig config;
    mutate(config);
    EXPECT_TRUE(
        test_support::throws_config_error_for_key([&] { OrbExtractor extractor(config); }, key));
  }
  // A pattern wider than the patch is refused too.
  OrbExtractorConfig small_patch;
  small_patch.patch_size = 21;
  small_patch.edge_threshold = 19;
  EXPECT_TRUE(test_support::throws_config_error_for_key(
      [&] { OrbExtractor extractor(small_patch); }, "orb.patch_size"))
      << "the radius-15 default pattern does not fit a 21-pixel patch";
}

// A level that is not more than 2 edge_threshold pixels wide or high holds no keypoint, yet took
// its share of num_features (review, stop 26: scale 2 with 8 levels lost 59 of 1000 at 640x480).
TEST(OrbExtractor, LevelsTooSmallForAKeypointAreAConfigurationError) {
  OrbExtractorConfig config;  // 8 levels of 1.2: level 7 of 640x480 is 179x134
  EXPECT_NO_THROW(config.validate_for_image(640, 480));
  config.scale_factor = 2.0;  // level 4 is 40x30, level 3 80x60
  try {
    config.validate_for_image(640, 480);
    FAIL() << "expected a ConfigError";
  } catch (const ConfigError& e) {
    const std::string what = e.what();
    EXPECT_NE(what.find("orb.num_levels"), std::string::npos) << what;
    EXPECT_NE(what.find("level 4"), std::string::npos) << what;
    EXPECT_NE(what.find("at most 4 levels"), std::string::npos) << what;
  }
  config.num_levels = 4;
  EXPECT_NO_THROW(config.validate_for_image(640, 480));
  // The check agrees with the extractor: the coarsest accepted level yields keypoints.
  const OrbFeatures features = OrbExtractor(config).extract(make_textured_image({640, 480}, 1));
  EXPECT_TRUE(std::any_of(features.keypoints.begin(), features.keypoints.end(),
                          [](const cv::KeyPoint& kp) { return kp.octave == 3; }));
  // An image too small for any keypoint names the edge.
  EXPECT_TRUE(test_support::throws_config_error_for_key(
      [&] { OrbExtractorConfig().validate_for_image(38, 480); }, "orb.edge_threshold"));
}

// The FAST cell threshold counts masked corners (a margin around dynamic objects, see the
// extractor): a cell with a strong corner under the mask still refuses the weak corners beside it.
TEST(OrbExtractor, AMaskedStrongCornerStillSetsItsCellsThreshold) {
  OrbExtractorConfig config;
  config.num_levels = 1;
  // Two blurred dots in the first FAST cell (x, y in [19, 49)) of a flat image: a bright one
  // (FAST response about 150: strong) and a faint one (about 17: only above the fallback
  // threshold 7). Blurred, so non-maximum suppression keeps one response per dot.
  cv::Mat image(480, 640, CV_32FC1, cv::Scalar(100));
  image.at<float>(26, 26) += 150.0f * 9.0f;
  image.at<float>(42, 42) += 13.0f * 9.0f;
  cv::GaussianBlur(image, image, cv::Size(0, 0), 1.0);
  image.convertTo(image, CV_8UC1);
  cv::Mat mask = cv::Mat::zeros(image.size(), CV_8UC1);
  cv::circle(mask, {26, 26}, 6, cv::Scalar(255), cv::FILLED);  // covers the bright dot only
  OrbExtractor extractor{config};
  auto count_near = [](const OrbFeatures& f, cv::Point2f p) {
    int n = 0;
    for (const cv::KeyPoint& kp : f.keypoints) n += cv::norm(kp.pt - p) < 3.0 ? 1 : 0;
    return n;
  };
  const OrbFeatures all = extractor.extract(image);
  ASSERT_EQ(count_near(all, {26, 26}), 1) << "precondition: the bright dot is found";
  ASSERT_EQ(count_near(all, {42, 42}), 0) << "precondition: its cell then refuses the faint dot";
  // Without the bright dot the faint one is found (the fallback threshold reaches it).
  cv::Mat faint_only = image.clone();
  faint_only(cv::Rect(16, 16, 20, 20)).setTo(100);
  ASSERT_EQ(count_near(extractor.extract(faint_only), {42, 42}), 1);
  const OrbFeatures masked = extractor.extract(image, mask);
  EXPECT_EQ(count_near(masked, {26, 26}), 0);
  EXPECT_EQ(count_near(masked, {42, 42}), 0) << "the masked bright dot still sets the threshold";
}

}  // namespace
}  // namespace ddl::features
