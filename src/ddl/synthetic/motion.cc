#include "ddl/synthetic/motion.h"

#include <cmath>

#include "ddl/core/error.h"
#include "ddl/synthetic/random.h"

namespace ddl::synthetic {
namespace {

constexpr double kDeg = M_PI / 180.0;

/// A seeded sum of sinusoids: amplitude * sum_k w_k sin(omega * f_k * t + phi_k), where the
/// frequency multipliers and phases come from the seed; peak value about `amplitude`.
double wave(std::uint64_t seed, std::uint64_t channel, double amplitude, double omega, double t) {
  Rng rng(hash2(seed, channel));
  const double f1 = rng.uniform(0.85, 1.15);
  const double f2 = rng.uniform(2.1, 2.9);
  const double p1 = rng.uniform(0, 2 * M_PI);
  const double p2 = rng.uniform(0, 2 * M_PI);
  return amplitude * (0.85 * std::sin(omega * f1 * t + p1) + 0.15 * std::sin(omega * f2 * t + p2));
}

/// Hand tremor: a few mm and a few tenths of a degree, 1-4 Hz.
SE3 tremor(std::uint64_t seed, double t, double scale) {
  Vec3d dp;
  Vec3d dr;
  for (int i = 0; i < 3; ++i) {
    dp[i] = wave(seed, 100 + i, 0.002 * scale, 2 * M_PI * 1.3, t) +
            wave(seed, 110 + i, 0.001 * scale, 2 * M_PI * 3.1, t);
    dr[i] = wave(seed, 120 + i, 0.25 * kDeg * scale, 2 * M_PI * 0.9, t) +
            wave(seed, 130 + i, 0.1 * kDeg * scale, 2 * M_PI * 3.7, t);
  }
  return SE3(so3_exp(dr), dp);
}

}  // namespace

std::string to_string(MotionType type) {
  switch (type) {
    case MotionType::kXyz:
      return "xyz";
    case MotionType::kStatic:
      return "static";
    case MotionType::kRpy:
      return "rpy";
    case MotionType::kHalfsphere:
      return "halfsphere";
    case MotionType::kLoop:
      return "loop";
  }
  return "?";
}

MotionType parse_motion_type(const std::string& text, const std::string& key) {
  for (auto t : {MotionType::kXyz, MotionType::kStatic, MotionType::kRpy, MotionType::kHalfsphere,
                 MotionType::kLoop}) {
    if (to_string(t) == text) return t;
  }
  throw ConfigError::for_key(
      key, fmt::format("unknown motion '{}' (expected xyz, static, rpy, halfsphere, loop)", text));
}

Mat3d look_at_rotation(const Vec3d& position_w, const Vec3d& target_w) {
  const Vec3d z_c = (target_w - position_w).normalized();
  Vec3d x_c = z_c.cross(Vec3d::UnitZ());
  if (x_c.norm() < 1e-9) x_c = Vec3d::UnitX();
  x_c.normalize();
  const Vec3d y_c = z_c.cross(x_c);
  Mat3d R;
  R.col(0) = x_c;
  R.col(1) = y_c;
  R.col(2) = z_c;
  return R;
}

SE3 camera_pose(const MotionConfig& c, double t) {
  const std::uint64_t seed = c.seed;
  const Mat3d R0 = look_at_rotation(c.base_position_w, c.look_at_w);
  switch (c.type) {
    case MotionType::kStatic:
      return SE3(R0, c.base_position_w) * tremor(seed, t, 1.0);
    case MotionType::kXyz: {
      // Along the camera's own axes, as TUM's xyz sequences: ~0.5 m peak to peak,
      // 0.2-0.4 m/s typical speed.
      const Vec3d d(wave(seed, 1, 0.26, 1.05, t), wave(seed, 2, 0.2, 1.25, t),
                    wave(seed, 3, 0.22, 0.9, t));
      return SE3(R0, c.base_position_w + R0 * d) * tremor(seed, t, 1.0);
    }
    case MotionType::kRpy: {
      const double roll = wave(seed, 4, 20 * kDeg, 1.1, t);
      const double pitch = wave(seed, 5, 15 * kDeg, 1.3, t);
      const double yaw = wave(seed, 6, 25 * kDeg, 0.95, t);
      const Mat3d R =
          R0 * so3_exp(Vec3d(0, yaw, 0)) * so3_exp(Vec3d(pitch, 0, 0)) * so3_exp(Vec3d(0, 0, roll));
      const Vec3d drift(wave(seed, 7, 0.03, 0.5, t), wave(seed, 8, 0.03, 0.6, t),
                        wave(seed, 9, 0.03, 0.55, t));
      return SE3(R, c.base_position_w + drift) * tremor(seed, t, 1.0);
    }
    case MotionType::kHalfsphere: {
      const Vec3d forward = R0.col(2);
      const Vec3d centre = c.base_position_w + 0.5 * forward;
      const double azimuth = wave(seed, 10, 60 * kDeg, 0.5, t);
      const double elevation = wave(seed, 11, 35 * kDeg, 0.65, t);
      // Direction from the centre back to the camera: -forward rotated by azimuth about world z
      // and by elevation about the camera's horizontal axis.
      const Vec3d horizontal_back = Vec3d(-forward.x(), -forward.y(), 0).normalized();
      const Vec3d az_dir = so3_exp(Vec3d(0, 0, azimuth)) * horizontal_back;
      const Vec3d dir = std::cos(elevation) * az_dir + std::sin(elevation) * Vec3d::UnitZ();
      const Vec3d position = centre + 0.5 * dir;
      const Mat3d R = look_at_rotation(position, centre);
      return SE3(R, position) * tremor(seed, t, 1.0);
    }
    case MotionType::kLoop: {
      const double phi = 2 * M_PI * t / c.loop_period_s - M_PI / 2;
      const Vec3d position =
          c.loop_centre_w + Vec3d(c.loop_radii_m.x() * std::cos(phi),
                                  c.loop_radii_m.y() * std::sin(phi), 0.08 * std::sin(2 * phi));
      // Outward normal of the ellipse, turned 35 deg towards the direction of travel, 12 deg down.
      const Vec3d outward =
          Vec3d(std::cos(phi) / c.loop_radii_m.x(), std::sin(phi) / c.loop_radii_m.y(), 0)
              .normalized();
      const Vec3d heading = so3_exp(Vec3d(0, 0, 35 * kDeg)) * outward;
      const Vec3d target = position + heading - Vec3d(0, 0, std::tan(12 * kDeg));
      // Tremor scaled by a periodic envelope so the last pose equals the first exactly.
      return SE3(look_at_rotation(position, target), position) *
             tremor(seed, t, std::sin(M_PI * t / c.loop_period_s));
    }
  }
  return SE3();
}

Vec3d kinect_accelerometer_reading(const MotionConfig& config, double t_s, Rng& noise,
                                   double noise_sigma) {
  constexpr double kStep = 0.01;  // s
  const Vec3d before = camera_pose(config, t_s - kStep).translation();
  const SE3 now = camera_pose(config, t_s);
  const Vec3d after = camera_pose(config, t_s + kStep).translation();
  const Vec3d acceleration_w = (after - 2.0 * now.translation() + before) / (kStep * kStep);
  const Vec3d force_c = now.rotation().transpose() * (acceleration_w + Vec3d(0, 0, 9.81));
  const Vec3d reading(-force_c.x(), -force_c.y(), force_c.z());  // optical -> Kinect axes
  return reading + noise_sigma * Vec3d(noise.normal(), noise.normal(), noise.normal());
}

}  // namespace ddl::synthetic
