#pragma once
// Synthetic scenes with exact ground truth for the optimisation tests.

#include <cmath>
#include <random>
#include <vector>

#include "ddl/core/se3.h"
#include "ddl/optimization/cost_functions.h"
#include "ddl/optimization/types.h"

namespace ddl::optimization::testing {

/// TUM freiburg1 intrinsics with ORB-SLAM2's TUM1 virtual baseline (bf = 40 px m).
inline CameraIntrinsics tum1_camera() {
  return {517.306408, 516.469215, 318.643040, 255.313989, 40.0};
}

inline constexpr double kImageWidth = 640.0;
inline constexpr double kImageHeight = 480.0;
inline constexpr double kScaleFactor = 1.2;  // ORB pyramid scale (ARCHITECTURE.md defaults)
inline constexpr int kLevels = 8;

inline double deg(double radians) { return radians * 180.0 / M_PI; }
inline double rad(double degrees) { return degrees * M_PI / 180.0; }

/// A pose perturbed by exactly `translation_m` metres along a random direction and exactly
/// `angle_rad` about a random axis (left-multiplied, i.e. in the camera frame for T_c_w).
inline SE3 perturb(const SE3& T, double translation_m, double angle_rad, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  const Vec3d dir = Vec3d(n(rng), n(rng), n(rng)).normalized();
  const Vec3d axis = Vec3d(n(rng), n(rng), n(rng)).normalized();
  return SE3(Mat3d(Eigen::AngleAxisd(angle_rad, axis)), translation_m * dir) * T;
}

/// Translation error [m] and rotation error [rad] between two poses.
inline double translation_error(const SE3& a, const SE3& b) {
  return (a.inverse().translation() - b.inverse().translation()).norm();
}
inline double rotation_error(const SE3& a, const SE3& b) {
  return (a * b.inverse()).rotation_angle();
}

/// Noise-free measurement of p_w from T_c_w; level picks 1/sigma^2 = scale^-2level.
inline Measurement measure(const CameraIntrinsics& cam, const SE3& T_c_w, const Vec3d& p_w,
                           bool stereo, int level) {
  const Vec3d p_c = T_c_w * p_w;
  Measurement m;
  m.uv_px = Vec2d(cam.fx * p_c.x() / p_c.z() + cam.cx, cam.fy * p_c.y() / p_c.z() + cam.cy);
  m.stereo = stereo;
  m.u_right_px = m.uv_px.x() - cam.bf / p_c.z();
  m.inv_sigma2 = 1.0 / std::pow(kScaleFactor * kScaleFactor, level);
  return m;
}

inline bool in_image(const Vec2d& uv) {
  return uv.x() >= 0.0 && uv.x() < kImageWidth && uv.y() >= 0.0 && uv.y() < kImageHeight;
}

/// A random point seen by the camera T_c_w at depth [near, far] inside the image.
inline Vec3d random_visible_point(const CameraIntrinsics& cam, const SE3& T_c_w, double near_m,
                                  double far_m, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, kImageWidth), v(0.0, kImageHeight),
      z(near_m, far_m);
  const double depth = z(rng);
  const Vec3d p_c((u(rng) - cam.cx) / cam.fx * depth, (v(rng) - cam.cy) / cam.fy * depth, depth);
  return T_c_w.inverse() * p_c;
}

/// Adds isotropic Gaussian pixel noise (sigma_px) to u, v and u_right.
inline void add_noise(Measurement* m, double sigma_px, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, sigma_px);
  m->uv_px += Vec2d(n(rng), n(rng));
  m->u_right_px += n(rng);
}

/// Replaces a measurement by a gross mismatch: a keypoint at least 20 px away from the true one,
/// with the depth of an unrelated pixel.
inline void make_gross_outlier(const CameraIntrinsics& cam, Measurement* m, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, kImageWidth), v(0.0, kImageHeight), z(0.5, 6.0);
  Vec2d uv;
  do {
    uv = Vec2d(u(rng), v(rng));
  } while ((uv - m->uv_px).norm() < 20.0);
  m->uv_px = uv;
  m->u_right_px = uv.x() - cam.bf / z(rng);
}

}  // namespace ddl::optimization::testing
