#include "ddl/eval/dense_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "ddl/synthetic/sequence.h"

namespace ddl::eval {
namespace {

TEST(DenseMetrics, PsnrOfAPatchWithAKnownError) {
  const cv::Mat background(480, 640, CV_8UC3, cv::Scalar(100, 120, 140));
  cv::Mat repaired = background.clone();
  cv::Mat mask = cv::Mat::zeros(480, 640, CV_8UC1);
  mask(cv::Rect(100, 100, 50, 40)).setTo(255);
  // +10 on every channel inside the patch: MSE 100, PSNR 10 log10(255^2 / 100) = 28.13 dB.
  repaired(cv::Rect(100, 100, 50, 40)) += cv::Scalar(10, 10, 10);
  // Errors outside the mask do not count.
  repaired(cv::Rect(300, 300, 10, 10)).setTo(cv::Scalar(0, 0, 0));
  const ColourError e = colour_error(repaired, background, mask);
  EXPECT_EQ(e.pixels, 2000u);
  EXPECT_NEAR(e.psnr_db(), 10.0 * std::log10(255.0 * 255.0 / 100.0), 1e-9);
  EXPECT_TRUE(std::isinf(colour_error(background, background, mask).psnr_db()));
  EXPECT_TRUE(std::isnan(ColourError{}.psnr_db()));
  // Pooling: a second patch with error 20 (MSE 400) of the same size gives MSE 250.
  ColourError pooled = e;
  ColourError other;
  other.sum_squared = 3.0 * 2000 * 400.0;
  other.pixels = 2000;
  pooled += other;
  EXPECT_NEAR(pooled.psnr_db(), 10.0 * std::log10(255.0 * 255.0 / 250.0), 1e-9);
}

TEST(DenseMetrics, InpaintedFrameAgainstItsBackground) {
  const cv::Size size(640, 480);
  const cv::Mat background_bgr(size, CV_8UC3, cv::Scalar(100, 100, 100));
  const cv::Mat background_depth(size, CV_32FC1, cv::Scalar(3.0f));
  cv::Mat dynamic = cv::Mat::zeros(size, CV_8UC1);
  const cv::Rect person(200, 100, 100, 200);  // 20000 px
  dynamic(person).setTo(255);
  // The original frame shows the person: black, at 1.5 m.
  cv::Mat original_bgr = background_bgr.clone();
  original_bgr(person).setTo(cv::Scalar(0, 0, 0));
  cv::Mat original_depth = background_depth.clone();
  original_depth(person).setTo(1.5f);
  // The run repaired a mask 5 px larger than the person, but left the top 50 rows unfilled;
  // the filled part has colour error 5 and depth error 0.04 m.
  cv::Mat repair_mask = cv::Mat::zeros(size, CV_8UC1);
  repair_mask(cv::Rect(195, 95, 110, 210)).setTo(255);
  cv::Mat unfilled = cv::Mat::zeros(size, CV_8UC1);
  unfilled(cv::Rect(195, 95, 110, 55)).setTo(255);
  cv::Mat repaired_bgr = original_bgr.clone();
  cv::Mat repaired_depth = original_depth.clone();
  const cv::Rect filled_part(195, 150, 110, 155);
  repaired_bgr(filled_part).setTo(cv::Scalar(105, 105, 105));
  repaired_depth(filled_part).setTo(3.04f);
  // Seen: the left half of the person.
  cv::Mat seen = cv::Mat::zeros(size, CV_8UC1);
  seen(cv::Rect(200, 100, 50, 200)).setTo(255);

  InpaintingFrameInputs in;
  in.repaired_bgr = repaired_bgr;
  in.repaired_depth_m = repaired_depth;
  in.repair_mask = repair_mask;
  in.unfilled = unfilled;
  in.original_bgr = original_bgr;
  in.original_depth_m = original_depth;
  in.dynamic_mask = dynamic;
  in.background_bgr = background_bgr;
  in.background_depth_m = background_depth;
  in.seen = seen;
  const InpaintingFrameMetrics m = evaluate_inpainted_frame(in);
  EXPECT_EQ(m.dynamic_px, 20000u);
  EXPECT_EQ(m.filled_px, 100u * 150u);  // rows 150..299 of the person
  EXPECT_EQ(m.seen_px, 10000u);
  EXPECT_EQ(m.filled_seen_px, 50u * 150u);
  EXPECT_EQ(m.repair_mask_px, 110u * 210u);
  EXPECT_NEAR(m.filled_rgb.psnr_db(), 10.0 * std::log10(255.0 * 255.0 / 25.0), 1e-9);
  // Unfilled baseline on the same pixels: black against 100.
  EXPECT_NEAR(m.filled_rgb_original.psnr_db(), 10.0 * std::log10(255.0 * 255.0 / 1e4), 1e-9);
  EXPECT_NEAR(m.filled_depth.median_m(), 0.04, 1e-6);
  EXPECT_NEAR(m.filled_depth_original.median_m(), 1.5, 1e-6);
  // Over all dynamic pixels: 15000 px with MSE 25, 5000 px (unfilled) with MSE 1e4.
  const double mse = (15000.0 * 25.0 + 5000.0 * 1e4) / 20000.0;
  EXPECT_NEAR(m.dynamic_rgb.psnr_db(), 10.0 * std::log10(255.0 * 255.0 / mse), 1e-9);
}

TEST(DenseMetrics, DepthErrorMedianSkipsMissingDepth) {
  cv::Mat a(1, 4, CV_32FC1), b(1, 4, CV_32FC1);
  a.at<float>(0, 0) = 1.0f;
  a.at<float>(0, 1) = 2.0f;
  a.at<float>(0, 2) = 0.0f;  // missing
  a.at<float>(0, 3) = 4.5f;
  b.setTo(1.5f);
  const DepthError e = depth_error(a, b, cv::Mat(1, 4, CV_8UC1, cv::Scalar(1)));
  EXPECT_EQ(e.abs_m.size(), 3u);
  EXPECT_EQ(e.missing, 1u);
  EXPECT_NEAR(e.median_m(), 0.5, 1e-6);  // {0.5, 0.5, 3.0}
  DepthError two;
  two.abs_m = {1.0f, 3.0f};
  EXPECT_NEAR(two.median_m(), 2.0, 1e-6);  // numpy.median of an even count
}

// A wall z = 3 (world = first camera), a "person" mask in the current frame.
TEST(DenseMetrics, SeenBackgroundNeedsAStaticDepthConsistentEarlierView) {
  const auto cam = synthetic::tum3_camera();
  const cv::Mat wall(cam.height, cam.width, CV_32FC1, cv::Scalar(3.0f));
  cv::Mat person = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
  person(cv::Rect(280, 140, 80, 200)).setTo(255);
  const SE3 T_w_cur;  // identity

  // An earlier view at the same pose with the person at the same place saw nothing behind it.
  EXPECT_EQ(cv::countNonZero(seen_background(person, wall, T_w_cur, {{SE3(), wall, person}}, cam)),
            0);
  // Moved 0.5 m to the right with no person: everything behind the person was seen.
  const SE3 T_w_right(Mat3d::Identity(), Vec3d(0.5, 0.0, 0.0));
  const cv::Mat empty = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
  EXPECT_EQ(
      cv::countNonZero(seen_background(person, wall, T_w_cur, {{T_w_right, wall, empty}}, cam)),
      80 * 200);
  // The same view, but something (not in its mask) 1.5 m away hid the wall: not seen.
  const cv::Mat near(cam.height, cam.width, CV_32FC1, cv::Scalar(1.5f));
  EXPECT_EQ(
      cv::countNonZero(seen_background(person, wall, T_w_cur, {{T_w_right, near, empty}}, cam)), 0);
  // Its own person mask over the left half of where the wall point lands: half is seen. The
  // wall points of the current person project 0.5 m * fx / 3 m = 89 px to the left.
  cv::Mat half = cv::Mat::zeros(cam.height, cam.width, CV_8UC1);
  half(cv::Rect(0, 0, 231, cam.height)).setTo(255);  // x < 231 covers u_cur < 320
  const int seen_px =
      cv::countNonZero(seen_background(person, wall, T_w_cur, {{T_w_right, wall, half}}, cam));
  EXPECT_NEAR(seen_px, 40 * 200, 2 * 200);
  // Pixels without background depth are never seen.
  const cv::Mat no_depth = cv::Mat::zeros(cam.height, cam.width, CV_32FC1);
  EXPECT_EQ(
      cv::countNonZero(seen_background(person, no_depth, T_w_cur, {{T_w_right, wall, empty}}, cam)),
      0);
}

TEST(DenseMetrics, VoxelClassesWithKnownGhosts) {
  const double res = 0.05;
  const double radius = 2 * res;
  PointGrid static_points(radius, radius / 10);
  PointGrid dynamic_points(radius, radius / 10);
  // Static: the floor z = 0 over 2 x 2 m, one point per cm.
  for (int i = 0; i <= 200; ++i) {
    for (int j = 0; j <= 200; ++j) static_points.insert(Vec3d(i * 0.01, j * 0.01, 0.0));
  }
  // Dynamic: a person-like slab standing on the floor at x = 1, y in [0.8, 1.2], z in [0, 1.7].
  for (int j = 0; j <= 40; ++j) {
    for (int k = 0; k <= 170; ++k) dynamic_points.insert(Vec3d(1.0, 0.8 + j * 0.01, k * 0.01));
  }
  EXPECT_LT(static_points.size(), 201u * 201u + 1);
  EXPECT_GT(static_points.size(), 30000u);  // merged to 1 cm cells, not thinned further

  std::vector<Vec3d> voxels;
  for (int i = 0; i < 38; ++i) {  // 38 x 5 floor voxels
    for (int j = 0; j < 5; ++j) voxels.emplace_back(0.025 + i * 0.05, 0.025 + j * 0.05, 0.025);
  }
  voxels.emplace_back(1.0, 1.0, 0.09);   // person's foot, within 2 voxels of the floor: static
  voxels.emplace_back(1.0, 1.0, 1.0);    // ghost
  voxels.emplace_back(1.02, 0.9, 1.5);   // ghost
  voxels.emplace_back(1.0, 1.0, 0.5);    // ghost
  voxels.emplace_back(1.0, 1.0, 0.125);  // ghost (0.125 from the floor, > 0.1)
  voxels.emplace_back(0.5, 0.5, 1.0);    // nothing near: other
  voxels.emplace_back(3.0, 3.0, 0.0);    // beyond the floor: other
  ASSERT_EQ(voxels.size(), 197u);
  const VoxelClasses c = classify_voxels(voxels, static_points, dynamic_points, radius);
  EXPECT_EQ(c.occupied, 197u);
  EXPECT_EQ(c.true_static, 191u);
  EXPECT_EQ(c.ghost, 4u);
  EXPECT_EQ(c.other, 2u);
  EXPECT_NEAR(100.0 * c.fraction(c.ghost), 100.0 * 4 / 197, 1e-9);
}

TEST(DenseMetrics, BadInputsAreRejected) {
  const cv::Mat a(10, 10, CV_8UC3, cv::Scalar::all(0));
  const cv::Mat b(10, 12, CV_8UC3, cv::Scalar::all(0));
  EXPECT_THROW(colour_error(a, b, cv::Mat::zeros(10, 10, CV_8UC1)), std::invalid_argument);
  EXPECT_THROW(colour_error(a, a, cv::Mat::zeros(10, 12, CV_8UC1)), std::invalid_argument);
  EXPECT_THROW(PointGrid(0.1, 0.2), std::invalid_argument);
  const PointGrid grid(0.1, 0.01);
  EXPECT_THROW((void)grid.any_within(Vec3d::Zero(), 0.2), std::invalid_argument);
}

}  // namespace
}  // namespace ddl::eval
