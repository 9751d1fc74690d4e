#pragma once
// TUM trajectory files: one pose per line, `timestamp tx ty tz qx qy qz qw`, T_w_c (camera in the
// world frame), '#' comments. Read as TUM's scripts read them (space, tab or comma separated;
// stamps out of order sorted, the last line of a repeated stamp kept, with a warning) but strictly:
// a malformed line, a missing file or an empty file throw ddl::InputError naming file and line.
// Lines holding NaN are skipped with a warning, as TUM's evaluate_rpe.py does.

#include <string>
#include <vector>

#include "ddl/core/se3.h"
#include "ddl/core/types.h"

namespace ddl::io {

struct StampedPose {
  double timestamp_s = 0.0;
  Vec3d t_w_c = Vec3d::Zero();               // camera position in the world frame
  Vec4d q_xyzw = Vec4d(0.0, 0.0, 0.0, 1.0);  // orientation as written in the file (qx qy qz qw)

  StampedPose() = default;
  StampedPose(double stamp, const SE3& T_w_c);
  /// The pose as an SE3 (quaternion normalised). Throws if the quaternion is zero.
  SE3 T_w_c() const;
};

using Trajectory = std::vector<StampedPose>;

Trajectory read_tum_trajectory(const std::string& path);

/// Writes full precision (shortest round-trip decimal), creating parent folders, whole or not at
/// all (core/filesystem.h). Throws ddl::OutputError if the file cannot be written.
void write_tum_trajectory(const std::string& path, const Trajectory& trajectory,
                          const std::string& header_comment = {});

}  // namespace ddl::io
