#include "ddl/eval/tracked.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "ddl/core/error.h"
#include "ddl/io/associate.h"
#include "ddl/io/text_table.h"

namespace ddl::eval {

std::vector<double> read_frame_stamps(const std::string& path) {
  std::vector<double> stamps;
  for (const io::TextRow& row : io::read_text_table(path)) {
    const double stamp = io::parse_double(row.fields[0], path, row.line);
    // NaN would break the sort below and with it the de-duplication (a wrong frame count).
    if (!std::isfinite(stamp)) {
      throw InputError::at_line(path, row.line,
                                fmt::format("timestamp '{}' is not finite", row.fields[0]));
    }
    stamps.push_back(stamp);
  }
  if (stamps.empty()) throw InputError::at(path, "no frames (empty frame list)");
  std::sort(stamps.begin(), stamps.end());
  stamps.erase(std::unique(stamps.begin(), stamps.end()), stamps.end());
  return stamps;
}

TrackedStats compute_tracked(const std::vector<double>& frame_stamps_s, const io::Trajectory& gt,
                             const io::Trajectory& est, double offset_s, double max_difference_s) {
  TrackedStats s;
  s.frames_total = frame_stamps_s.size();
  if (gt.empty()) return s;
  const double t0 = gt.front().timestamp_s;
  const double t1 = gt.back().timestamp_s;
  // The frames are on the estimate's clock, the ground truth on its own: a frame stamped t is in
  // its span when t + offset is (until stop 32 the offset was applied to the wrong side, and a
  // non-zero --offset miscounted: 484 instead of 694 of fr1_rpy's 694 frames at 0.05 s).
  std::vector<double> frames;
  for (double t : frame_stamps_s) {
    if (t + offset_s >= t0 && t + offset_s <= t1) frames.push_back(t);
  }
  std::vector<double> est_stamps;
  est_stamps.reserve(est.size());
  for (const io::StampedPose& p : est) {
    est_stamps.push_back(p.timestamp_s);
    if (p.timestamp_s + offset_s >= t0 && p.timestamp_s + offset_s <= t1) ++s.est_poses_in_gt_span;
  }
  s.frames_in_gt_span = frames.size();
  s.tracked_frames = io::associate(frames, est_stamps, 0.0, max_difference_s).size();
  s.ratio = frames.empty()
                ? std::numeric_limits<double>::quiet_NaN()
                : static_cast<double>(s.tracked_frames) / static_cast<double>(s.frames_in_gt_span);
  return s;
}

}  // namespace ddl::eval
