#pragma once
// Tracked ratio: how many of the frames that ground truth covers received an estimated pose.
// ATE and RPE silently ignore frames without a pose (a tracker that is lost half the time can
// still show a small ATE), so the evaluation reports this beside them.
//
// frames_in_gt_span: frames (from a TUM rgb.txt or associations.txt: first column = rgb stamp)
// with first_gt_stamp <= t <= last_gt_stamp. tracked_frames: those of them that associate with an
// estimated pose (io::associate, |t_frame - (t_est + offset)| < max_difference, one-to-one).
// ratio = tracked_frames / frames_in_gt_span.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "ddl/io/trajectory_io.h"

namespace ddl::eval {

struct TrackedStats {
  std::size_t frames_total = 0;          // distinct frame stamps in the frames file
  std::size_t frames_in_gt_span = 0;     // frames inside the ground-truth time span
  std::size_t tracked_frames = 0;        // of those, frames with an estimated pose
  std::size_t est_poses_in_gt_span = 0;  // estimated poses (stamp + offset) inside the span
  double ratio = 0.0;  // tracked_frames / frames_in_gt_span (NaN when no frame is in the span)
};

/// First column of every non-comment line, as seconds, sorted, duplicates removed (TUM's scripts
/// key these files by stamp). Throws ddl::InputError naming file and line for a non-numeric
/// stamp, and naming the file when it is missing or holds no frames.
std::vector<double> read_frame_stamps(const std::string& path);

TrackedStats compute_tracked(const std::vector<double>& frame_stamps_s, const io::Trajectory& gt,
                             const io::Trajectory& est, double offset_s = 0.0,
                             double max_difference_s = 0.02);

}  // namespace ddl::eval
