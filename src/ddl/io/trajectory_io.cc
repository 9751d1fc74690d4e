#include "ddl/io/trajectory_io.h"

#include <fmt/format.h>
#include <fmt/os.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <sstream>

#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"
#include "ddl/io/text_table.h"

namespace ddl::io {

StampedPose::StampedPose(double stamp, const SE3& T_w_c)
    : timestamp_s(stamp),
      t_w_c(T_w_c.translation()),
      q_xyzw(T_w_c.quaternion().x(), T_w_c.quaternion().y(), T_w_c.quaternion().z(),
             T_w_c.quaternion().w()) {}

SE3 StampedPose::T_w_c() const {
  if (q_xyzw.norm() == 0.0)
    throw Error(fmt::format("pose at {} has a zero quaternion", timestamp_s));
  return SE3(Quatd(q_xyzw[3], q_xyzw[0], q_xyzw[1], q_xyzw[2]), t_w_c);
}

Trajectory read_tum_trajectory(const std::string& path) {
  Trajectory out;
  std::size_t skipped_nan = 0;
  std::size_t out_of_order = 0;  // lines whose stamp is not above the line before
  std::size_t first_out_of_order = 0;
  double latest_s = -std::numeric_limits<double>::infinity();  // the latest stamp so far
  for (const TextRow& row : read_text_table(path)) {
    if (row.fields.size() != 8) {
      throw InputError::at_line(
          path, row.line,
          fmt::format("expected 8 values 'timestamp tx ty tz qx qy qz qw', found {}",
                      row.fields.size()));
    }
    double v[8];
    bool has_nan = false;
    for (int k = 0; k < 8; ++k) {
      v[k] = parse_double(row.fields[static_cast<std::size_t>(k)], path, row.line);
      has_nan = has_nan || std::isnan(v[k]);
    }
    if (has_nan) {
      ++skipped_nan;
      continue;
    }
    for (double x : v) {
      if (!std::isfinite(x)) throw InputError::at_line(path, row.line, "infinite value");
    }
    if (!out.empty() && v[0] <= latest_s) {
      ++out_of_order;
      if (first_out_of_order == 0) first_out_of_order = row.line;
    }
    latest_s = std::max(latest_s, v[0]);
    StampedPose p;
    p.timestamp_s = v[0];
    p.t_w_c = Vec3d(v[1], v[2], v[3]);
    p.q_xyzw = Vec4d(v[4], v[5], v[6], v[7]);
    out.push_back(p);
  }
  if (skipped_nan > 0) spdlog::warn("{}: skipped {} line(s) holding NaN", path, skipped_nan);
  if (out.empty()) throw InputError::at(path, "no poses (empty trajectory file)");
  if (out_of_order > 0) {
    // As TUM's tools read the file (a dict keyed by stamp, then sorted): in time order, the last
    // line of a repeated stamp kept.
    std::stable_sort(out.begin(), out.end(), [](const StampedPose& a, const StampedPose& b) {
      return a.timestamp_s < b.timestamp_s;
    });
    Trajectory unique;
    unique.reserve(out.size());
    for (const StampedPose& p : out) {
      if (!unique.empty() && unique.back().timestamp_s == p.timestamp_s) {
        unique.back() = p;
      } else {
        unique.push_back(p);
      }
    }
    spdlog::warn(
        "{}: {} line(s) do not increase in time (first: line {}); read as TUM's tools do, sorted "
        "by time with the last line of a repeated stamp kept ({} poses)",
        path, out_of_order, first_out_of_order, unique.size());
    out = std::move(unique);
  }
  return out;
}

void write_tum_trajectory(const std::string& path, const Trajectory& trajectory,
                          const std::string& header_comment) {
  write_file_atomically(path, "the trajectory", [&](std::ostream& file) {
    if (!header_comment.empty()) file << "# " << header_comment << '\n';
    file << "# timestamp tx ty tz qx qy qz qw\n";
    for (const StampedPose& s : trajectory) {
      file << fmt::format("{} {} {} {} {} {} {} {}\n", s.timestamp_s, s.t_w_c.x(), s.t_w_c.y(),
                          s.t_w_c.z(), s.q_xyzw[0], s.q_xyzw[1], s.q_xyzw[2], s.q_xyzw[3]);
    }
    return true;
  });
}

}  // namespace ddl::io
