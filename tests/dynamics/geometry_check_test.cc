#include "ddl/dynamics/geometry_check.h"

#include <gtest/gtest.h>

#include <random>

#include "ddl/core/error.h"
#include "ddl/dynamics/mask_fusion.h"

namespace ddl::dynamics {
namespace {

camera::PinholeCamera test_camera() {
  camera::PinholeCamera c;
  c.fx = 535.4;
  c.fy = 539.2;
  c.cx = 320.1;
  c.cy = 247.6;
  return c;
}

// Depth image of a fronto-parallel wall at wall_z (world z, camera looking along +z from
// T_w_c), with an optional box [x0,x1]x[y0,y1] at box_z in world coordinates.
struct Box {
  double x0, x1, y0, y1, z;
};

cv::Mat render_depth(const camera::PinholeCamera& cam, const SE3& T_w_c, double wall_z,
                     const std::vector<Box>& boxes) {
  cv::Mat depth(cam.height, cam.width, CV_32FC1);
  const Vec3d o = T_w_c.translation();
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Vec3d dir = T_w_c.rotation() * cam.unproject(u, v, 1.0);
      double t = (wall_z - o.z()) / dir.z();
      for (const Box& b : boxes) {
        const double tb = (b.z - o.z()) / dir.z();
        const Vec3d p = o + tb * dir;
        if (tb > 0 && tb < t && p.x() >= b.x0 && p.x() <= b.x1 && p.y() >= b.y0 && p.y() <= b.y1) {
          t = tb;
        }
      }
      // Camera-frame z of the hit point.
      depth.at<float>(v, u) = static_cast<float>((T_w_c.inverse() * (o + t * dir)).z());
    }
  }
  return depth;
}

ReferenceView reference_from(const camera::PinholeCamera& cam, const SE3& T_w_c,
                             const cv::Mat& depth, int count, unsigned seed) {
  ReferenceView ref;
  ref.T_w_c = T_w_c;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<float> u(5, cam.width - 6), v(5, cam.height - 6);
  for (int i = 0; i < count; ++i) {
    const cv::Point2f p(u(rng), v(rng));
    ref.pixels.push_back(p);
    ref.depth_m.push_back(depth.at<float>(cvRound(p.y), cvRound(p.x)));
  }
  ref.depth_image_m = depth;
  return ref;
}

cv::Mat truth_mask(const cv::Mat& with, const cv::Mat& without) {
  cv::Mat diff;
  cv::absdiff(with, without, diff);
  return diff > 0.01f;
}

TEST(GeometryCheck, FindsAnObjectThatAppearedInFront) {
  const auto cam = test_camera();
  const SE3 T_w_ref(Mat3d::Identity(), Vec3d(0, 0, 0));
  const SE3 T_w_cur(Mat3d(Eigen::AngleAxisd(0.05, Vec3d::UnitY())), Vec3d(0.1, 0.0, 0.05));
  const cv::Mat ref_depth = render_depth(cam, T_w_ref, 3.0, {});
  const std::vector<Box> person = {{-0.3, 0.2, -0.6, 0.9, 1.6}};
  const cv::Mat cur_depth = render_depth(cam, T_w_cur, 3.0, person);
  const cv::Mat truth = truth_mask(cur_depth, render_depth(cam, T_w_cur, 3.0, {}));
  GeometryCheckConfig config;
  GeometryCheckStats stats;
  const cv::Mat mask = geometry_dynamic_mask(cur_depth, T_w_cur.inverse(),
                                             {reference_from(cam, T_w_ref, ref_depth, 1000, 1)},
                                             cam, config, &stats);
  const MaskScore score = score_mask(mask, truth);
  EXPECT_GT(stats.points_dynamic, 20);
  EXPECT_GT(score.iou, 0.85) << "precision " << score.precision << " recall " << score.recall;
}

TEST(GeometryCheck, StaticSceneGivesAnEmptyMask) {
  const auto cam = test_camera();
  const SE3 T_w_ref;
  const SE3 T_w_cur(Mat3d(Eigen::AngleAxisd(0.1, Vec3d::UnitX())), Vec3d(0.2, -0.1, 0.3));
  const std::vector<Box> table = {{-0.5, 0.5, 0.2, 0.8, 2.2}};
  const cv::Mat ref_depth = render_depth(cam, T_w_ref, 3.0, table);
  const cv::Mat cur_depth = render_depth(cam, T_w_cur, 3.0, table);
  const cv::Mat mask = geometry_dynamic_mask(cur_depth, T_w_cur.inverse(),
                                             {reference_from(cam, T_w_ref, ref_depth, 1000, 2)},
                                             cam, GeometryCheckConfig{});
  // Depth edges of a static box seen from two viewpoints: at most a few stray pixels.
  EXPECT_LT(cv::countNonZero(mask), 0.005 * static_cast<double>(mask.total()));
}

TEST(GeometryCheck, CatchesAMovedObjectOfAStaticClass) {
  const auto cam = test_camera();
  const SE3 T_w_ref;
  const SE3 T_w_cur(Mat3d::Identity(), Vec3d(0.05, 0, 0));
  const Box book_before{-0.8, -0.5, 0.0, 0.3, 2.0};
  const Box book_after{0.4, 0.7, 0.0, 0.3, 2.0};
  const cv::Mat ref_depth = render_depth(cam, T_w_ref, 3.0, {book_before});
  const cv::Mat cur_depth = render_depth(cam, T_w_cur, 3.0, {book_after});
  const cv::Mat truth = truth_mask(cur_depth, render_depth(cam, T_w_cur, 3.0, {}));
  const cv::Mat mask = geometry_dynamic_mask(cur_depth, T_w_cur.inverse(),
                                             {reference_from(cam, T_w_ref, ref_depth, 1500, 3)},
                                             cam, GeometryCheckConfig{});
  const MaskScore score = score_mask(mask, truth);
  EXPECT_GT(score.iou, 0.8) << "precision " << score.precision << " recall " << score.recall;
}

TEST(GeometryCheck, WideParallaxPointsAreSkipped) {
  const auto cam = test_camera();
  // Reference 2 m to the side looking at the same wall point: rays differ by more than 30 deg
  // for the points in the middle of the current view.
  const SE3 T_w_ref(Mat3d(Eigen::AngleAxisd(-0.6, Vec3d::UnitY())), Vec3d(2.0, 0, 0));
  const SE3 T_w_cur;
  const cv::Mat ref_depth = render_depth(cam, T_w_ref, 3.0, {});
  const cv::Mat cur_depth = render_depth(cam, T_w_cur, 3.0, {});
  GeometryCheckConfig config;
  GeometryCheckStats stats;
  geometry_dynamic_mask(cur_depth, T_w_cur.inverse(),
                        {reference_from(cam, T_w_ref, ref_depth, 500, 4)}, cam, config, &stats);
  EXPECT_GT(stats.points_skipped_parallax, 0);
  config.max_parallax_deg = 89.0;
  GeometryCheckStats wide;
  geometry_dynamic_mask(cur_depth, T_w_cur.inverse(),
                        {reference_from(cam, T_w_ref, ref_depth, 500, 4)}, cam, config, &wide);
  EXPECT_EQ(wide.points_skipped_parallax, 0);
}

TEST(MaskFusion, CombineAndScore) {
  cv::Mat a = cv::Mat::zeros(10, 10, CV_8UC1);
  cv::Mat b = cv::Mat::zeros(10, 10, CV_8UC1);
  a(cv::Rect(0, 0, 5, 10)).setTo(255);
  b(cv::Rect(5, 0, 5, 10)).setTo(255);
  EXPECT_EQ(cv::countNonZero(combine_masks(a, b)), 100);
  EXPECT_EQ(cv::countNonZero(combine_masks(a, cv::Mat())), 50);
  const MaskScore s = score_mask(a, combine_masks(a, b));
  EXPECT_DOUBLE_EQ(s.iou, 0.5);
  EXPECT_DOUBLE_EQ(s.precision, 1.0);
  EXPECT_DOUBLE_EQ(s.recall, 0.5);
  EXPECT_GT(cv::countNonZero(feature_exclusion_mask(a, 2)), 50);
}

TEST(GeometryCheck, ConfigErrorsNameTheKey) {
  GeometryCheckConfig config;
  config.max_parallax_deg = 0;
  try {
    config.validate();
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("dynamics.max_parallax_deg"), std::string::npos);
  }
}

}  // namespace
}  // namespace ddl::dynamics
