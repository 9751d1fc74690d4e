// DepthTimeAligner: a depth image captured at another instant than its colour image is brought
// to the colour image's instant with the motion between two tracked frames.
#include "ddl/pipeline/depth_time_aligner.h"

#include <gtest/gtest.h>

#include <cmath>

#include "card_scene.h"

namespace ddl::pipeline {
namespace {

using test_support::card_scene_camera;
using test_support::render_card_scene;

/// A camera turning at a constant 60 deg/s about a tilted axis and moving at 0.3 m/s: the pose
/// at time t (seconds) from the origin.
SE3 pose_at(double t) {
  const Vec3d omega = Vec3d(0.3, 1.0, 0.2).normalized() * (60.0 * M_PI / 180.0);
  const Vec3d velocity(0.3, 0.0, 0.05);
  Vec6d xi;
  xi << velocity * t, omega * t;
  return SE3::exp(xi);
}

double share_within(const cv::Mat& a, const cv::Mat& b, float tolerance_m) {
  int close = 0;
  for (int v = 0; v < a.rows; ++v) {
    for (int u = 0; u < a.cols; ++u) {
      if (std::abs(a.at<float>(v, u) - b.at<float>(v, u)) < tolerance_m) ++close;
    }
  }
  return static_cast<double>(close) / static_cast<double>(a.total());
}

TEST(DepthTimeAligner, ADepthImageTakenEarlierIsMovedToTheColourImagesInstant) {
  camera::PinholeCamera cam = card_scene_camera();
  cam.depth_time_offset_s = -0.020;  // captured 20 ms before its stamp, as tum1's
  const DepthTimeAligner aligner(cam, true);
  ASSERT_TRUE(aligner.active());
  // Frame k at t = 1/30 s, its depth stamped 8 ms after the colour: captured 12 ms before it.
  const double t_prev = 0.0, t = 1.0 / 30.0;
  io::RgbdFrame frame;
  frame.timestamp_s = t;
  frame.depth_timestamp_s = t + 0.008;
  EXPECT_NEAR(aligner.shift_s(frame), -0.012, 1e-12);
  frame.depth_m = render_card_scene(cam, pose_at(t - 0.012));
  const cv::Mat truth = render_card_scene(cam, pose_at(t));
  // The motion from the previous frame's camera into this one's: T_c(k)_c(k-1).
  const SE3 velocity = pose_at(t).inverse() * pose_at(t_prev);
  DepthAlignment what;
  const cv::Mat aligned = aligner.align(frame, velocity, t - t_prev, &what);
  EXPECT_TRUE(what.moved);
  EXPECT_NEAR(what.shift_s, -0.012, 1e-12);
  EXPECT_NEAR(what.rotation_deg, 60.0 * 0.012, 1e-3);
  EXPECT_LT(share_within(frame.depth_m, truth, 0.005f), 0.3);  // as read: off the colour's view
  EXPECT_GT(share_within(aligned, truth, 0.005f), 0.95);
}

TEST(DepthTimeAligner, NothingMovesWithoutAnOffsetAVelocityOrAShift) {
  camera::PinholeCamera cam = card_scene_camera();
  io::RgbdFrame frame;
  frame.timestamp_s = 1.0;
  frame.depth_timestamp_s = 1.010;
  frame.depth_m = render_card_scene(cam, SE3());
  const SE3 velocity = pose_at(1.0 / 30.0).inverse();
  DepthAlignment what;
  // A synchronised camera (no depth_time_offset_s): whatever the stamps say.
  const DepthTimeAligner synchronised(cam, true);
  EXPECT_FALSE(synchronised.active());
  EXPECT_EQ(synchronised.shift_s(frame), 0.0);
  EXPECT_EQ(synchronised.align(frame, velocity, 1.0 / 30.0, &what).data, frame.depth_m.data);
  EXPECT_FALSE(what.moved);
  cam.depth_time_offset_s = -0.010;
  // Switched off.
  EXPECT_FALSE(DepthTimeAligner(cam, false).active());
  const DepthTimeAligner aligner(cam, true);
  // No velocity (the first frame, after a loss).
  EXPECT_EQ(aligner.align(frame, std::nullopt, 1.0 / 30.0, &what).data, frame.depth_m.data);
  EXPECT_FALSE(what.moved);
  // Captured with the colour: the stamp and the offset cancel.
  EXPECT_NEAR(aligner.shift_s(frame), 0.0, 1e-9);
  EXPECT_EQ(aligner.align(frame, velocity, 1.0 / 30.0, &what).data, frame.depth_m.data);
  EXPECT_FALSE(what.moved);
  // No depth stamp: the colour's, so the shift is the offset.
  frame.depth_timestamp_s.reset();
  EXPECT_NEAR(aligner.shift_s(frame), -0.010, 1e-12);
}

}  // namespace
}  // namespace ddl::pipeline
