#pragma once
// The accelerometer log of a TUM RGB-D sequence (<dir>/accelerometer.txt, `timestamp ax ay az`,
// m/s^2, '#' comments) and the direction "up" it gives in the colour camera's frame.
//
// A resting accelerometer measures the specific force, which points up with magnitude g. The
// Kinect's readings are in axes x left, y up, z forward, the camera's optical frame turned half a
// turn about its z axis: up in the camera frame (x right, y down, z forward) is (-ax, -ay, az)
// normalised. Measured on fr1_rpy against its ground truth (docs/datasets.md, Accelerometer).
// Hand-held motion adds its own acceleration (about 1 m/s^2, a few degrees); readings are
// averaged over a short window around each frame's stamp.
//
// Threads: immutable after construction; const methods may be called from any thread.

#include <optional>
#include <string>
#include <vector>

#include "ddl/core/types.h"

namespace ddl::io {

struct AccelerometerSample {
  double timestamp_s = 0.0;
  Vec3d specific_force;  // m/s^2, in the accelerometer's axes (x left, y up, z forward)
};

/// Up in the camera's optical frame from one reading in the Kinect accelerometer's axes; nullopt
/// when its norm is outside [min_norm_mps2, max_norm_mps2] (a missing sensor writes zeros, a hard
/// knock reads far more than g).
std::optional<Vec3d> up_in_camera_from_accelerometer(const Vec3d& specific_force,
                                                     double min_norm_mps2 = 5.0,
                                                     double max_norm_mps2 = 15.0);

class AccelerometerLog {
 public:
  /// Reads `path`. Throws ddl::InputError naming the file and line (wrong field count, a
  /// non-numeric or non-finite value, a timestamp that decreases).
  static AccelerometerLog read(const std::string& path);

  explicit AccelerometerLog(std::vector<AccelerometerSample> samples);

  /// Readings within this many seconds of a frame's stamp make its up direction.
  static constexpr double kDefaultHalfWindowS = 0.02;

  /// Up in the camera frame at `stamp_s`: the mean of the readings within `half_window_s` of it,
  /// converted by up_in_camera_from_accelerometer. nullopt when no reading lies that close or
  /// their mean is not a plausible gravity reading.
  std::optional<Vec3d> up_in_camera_at(double stamp_s,
                                       double half_window_s = kDefaultHalfWindowS) const;

  const std::vector<AccelerometerSample>& samples() const { return samples_; }
  bool empty() const { return samples_.empty(); }

 private:
  std::vector<AccelerometerSample> samples_;  // by increasing timestamp
};

}  // namespace ddl::io
