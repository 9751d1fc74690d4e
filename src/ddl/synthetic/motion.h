#pragma once
// Hand-held camera motions mirroring the TUM RGB-D categories. Every motion is a sum of
// sinusoids (C-infinity, so velocity and acceleration are continuous), seeded for phases, and
// returns T_w_c (camera to world; camera x right, y down, z forward) at time t_s from the start.
//
//   xyz         translation along x, y, z of about 0.5 m peak to peak, orientation nearly fixed
//   static      nearly still: hand tremor of a few mm and a few tenths of a degree
//   rpy         rotation about the optical axis (roll, +-20 deg), x (pitch, +-15 deg) and
//               y (yaw, +-25 deg) at 15-40 deg/s, position nearly fixed
//   halfsphere  on the rear half of a sphere of 1 m diameter centred 0.5 m in front of the base
//               position, always looking at the sphere's centre (so towards the scene),
//               azimuth +-60 deg, elevation +-35 deg
//   loop        once around an ellipse through the room (one full turn over `loop_period_s`),
//               looking outwards at the walls; the last frame returns to the first pose
// All but `static` also get the tremor, as a real hand does.

#include <cstdint>
#include <string>
#include <vector>

#include "ddl/core/se3.h"
#include "ddl/core/types.h"
#include "ddl/synthetic/random.h"

namespace ddl::synthetic {

enum class MotionType { kXyz, kStatic, kRpy, kHalfsphere, kLoop };

/// "xyz", "static", "rpy", "halfsphere", "loop".
std::string to_string(MotionType type);
/// Throws ddl::ConfigError naming `key` for an unknown name.
MotionType parse_motion_type(const std::string& text, const std::string& key = "motion");

struct MotionConfig {
  MotionType type = MotionType::kXyz;
  Vec3d base_position_w = Vec3d(3.0, 1.1, 1.45);  // centre of the motion
  Vec3d look_at_w = Vec3d(3.0, 4.2, 0.95);        // what the base pose looks at
  Vec3d loop_centre_w = Vec3d(3.0, 2.25, 1.4);    // loop: ellipse centre
  Vec2d loop_radii_m = Vec2d(1.65, 0.8);          // loop: semi-axes along x and y
  double loop_period_s = 30.0;                    // loop: duration of one turn
  std::uint64_t seed = 1;                         // phases of the sinusoids
};

/// Rotation of a camera at `position` looking at `target` with world z up (no roll).
Mat3d look_at_rotation(const Vec3d& position_w, const Vec3d& target_w);

/// T_w_c at time t_s (seconds from the sequence start).
SE3 camera_pose(const MotionConfig& config, double t_s);

/// What a Kinect's accelerometer on the camera of `config` reads at time t_s: the specific force
/// (the camera's acceleration, by central differences over 10 ms, plus 9.81 m/s^2 up the world
/// z axis) in the sensor's axes (x left, y up, z forward; io/accelerometer.h), with
/// `noise_sigma` m/s^2 of Gaussian noise per axis drawn from `noise`.
Vec3d kinect_accelerometer_reading(const MotionConfig& config, double t_s, Rng& noise,
                                   double noise_sigma = 0.05);

}  // namespace ddl::synthetic
