#include "ddl/io/accelerometer.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <utility>

#include "ddl/core/error.h"
#include "ddl/io/text_table.h"

namespace ddl::io {

std::optional<Vec3d> up_in_camera_from_accelerometer(const Vec3d& specific_force,
                                                     double min_norm_mps2, double max_norm_mps2) {
  const double g = specific_force.norm();
  if (!(g >= min_norm_mps2 && g <= max_norm_mps2)) return std::nullopt;
  // Kinect accelerometer axes (x left, y up, z forward) -> optical frame (x right, y down).
  return Vec3d(-specific_force.x(), -specific_force.y(), specific_force.z()) / g;
}

AccelerometerLog AccelerometerLog::read(const std::string& path) {
  std::vector<AccelerometerSample> samples;
  for (const TextRow& row : read_text_table(path)) {
    if (row.fields.size() != 4) {
      throw InputError::at_line(
          path, row.line,
          fmt::format("expected `timestamp ax ay az`, found {} fields", row.fields.size()));
    }
    AccelerometerSample s;
    s.timestamp_s = parse_double(row.fields[0], path, row.line);
    for (int k = 0; k < 3; ++k) {
      s.specific_force[k] =
          parse_double(row.fields[static_cast<std::size_t>(k) + 1], path, row.line);
    }
    if (!std::isfinite(s.timestamp_s) || !s.specific_force.allFinite()) {
      throw InputError::at_line(path, row.line, "a value is not a finite number");
    }
    if (!samples.empty() && s.timestamp_s < samples.back().timestamp_s) {
      throw InputError::at_line(path, row.line,
                                fmt::format("timestamp {:.6f} is before the previous one ({:.6f})",
                                            s.timestamp_s, samples.back().timestamp_s));
    }
    samples.push_back(s);
  }
  return AccelerometerLog(std::move(samples));
}

AccelerometerLog::AccelerometerLog(std::vector<AccelerometerSample> samples)
    : samples_(std::move(samples)) {}

std::optional<Vec3d> AccelerometerLog::up_in_camera_at(double stamp_s, double half_window_s) const {
  const auto first =
      std::lower_bound(samples_.begin(), samples_.end(), stamp_s - half_window_s,
                       [](const AccelerometerSample& s, double t) { return s.timestamp_s < t; });
  Vec3d sum = Vec3d::Zero();
  int n = 0;
  for (auto it = first; it != samples_.end() && it->timestamp_s <= stamp_s + half_window_s; ++it) {
    sum += it->specific_force;
    ++n;
  }
  if (n == 0) return std::nullopt;
  return up_in_camera_from_accelerometer(sum / n);
}

}  // namespace ddl::io
