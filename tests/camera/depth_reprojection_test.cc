// camera::reproject_depth: a depth image moved to another pose of its camera must match the
// depth rendered at that pose, with the nearer surface in front where two meet.
#include "ddl/camera/depth_reprojection.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "card_scene.h"

namespace ddl::camera {
namespace {

using test_support::card_scene_camera;
using test_support::render_card_scene;

TEST(DepthReprojection, TheIdentityGivesTheImageBack) {
  const PinholeCamera cam = card_scene_camera();
  const cv::Mat depth = render_card_scene(cam, SE3());
  const cv::Mat out = reproject_depth(depth, SE3(), cam);
  double max_error = 0.0;
  cv::minMaxLoc(cv::abs(out - depth), nullptr, &max_error);
  EXPECT_LT(max_error, 1e-5);
}

TEST(DepthReprojection, AMovedImageMatchesTheSceneRenderedAtTheOtherPose) {
  const PinholeCamera cam = card_scene_camera();
  // Two degrees about a tilted axis and two centimetres: a fast turn of a hand-held camera
  // over 20-40 ms.
  const SE3 T_w_source;
  const SE3 T_w_target = SE3::exp((Vec6d() << 0.02, -0.01, 0.005, 0.01, 0.03, 0.012).finished());
  const cv::Mat source = render_card_scene(cam, T_w_source);
  const cv::Mat truth = render_card_scene(cam, T_w_target);
  const cv::Mat moved = reproject_depth(source, T_w_target.inverse() * T_w_source, cam);
  const cv::Mat as_read_error = cv::abs(source - truth);
  const cv::Mat moved_error = cv::abs(moved - truth);
  int close = 0, close_as_read = 0, empty = 0;
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      if (moved.at<float>(v, u) == 0.0f) ++empty;
      if (moved_error.at<float>(v, u) < 0.005f) ++close;
      if (as_read_error.at<float>(v, u) < 0.005f) ++close_as_read;
    }
  }
  const double n = cam.width * cam.height;
  // Empty: the border the source did not see and the wall the card hid from it.
  EXPECT_LT(empty / n, 0.06);
  EXPECT_GT(close / n, 0.93);
  EXPECT_LT(close_as_read / n, 0.2);  // the wall's depth changes across the image as it turns
  // The card stays in front of the wall that lands on the same pixels: its centre, at the
  // target pose, reads 1.5 m along the ray.
  const Vec3d centre_c = T_w_target.inverse() * Vec3d(0, 0, 1.5);
  const Vec2d uv = cam.project(centre_c);
  EXPECT_NEAR(
      moved.at<float>(static_cast<int>(std::lround(uv.y())), static_cast<int>(std::lround(uv.x()))),
      centre_c.z(), 0.005);
}

TEST(DepthReprojection, AnImageOfAnotherTypeOrSizeIsRefused) {
  const PinholeCamera cam = card_scene_camera();
  EXPECT_THROW(reproject_depth(cv::Mat(cam.height, cam.width, CV_16UC1), SE3(), cam),
               std::invalid_argument);
  EXPECT_THROW(reproject_depth(cv::Mat(10, 10, CV_32FC1), SE3(), cam), std::invalid_argument);
}

}  // namespace
}  // namespace ddl::camera
