#pragma once
// Absolute trajectory error exactly as the TUM RGB-D benchmark's evaluate_ate.py:
//  1. ground-truth and estimated stamps are associated as associate.py does (|t_gt - (t_est +
//     offset)| < max_difference, greedy by smallest difference, one-to-one; ddl::io::associate);
//  2. the estimate's positions (times `scale`) of the associated pairs are aligned onto the
//     ground truth's by Horn's method (rigid, evaluate_ate.py's align()), or optionally by Umeyama
//     with a scale factor (not in the script);
//  3. the error of each pair is the distance between the ground-truth position and the aligned
//     estimated position; statistics as numpy (stats.h).
// Only positions are used; orientations (including zero quaternions) are ignored, as in the script.
// Lost frames (no estimated pose) are silently absent from ATE: see tracked.h.

#include <Eigen/Core>
#include <cstddef>
#include <vector>

#include "ddl/eval/alignment.h"
#include "ddl/eval/stats.h"
#include "ddl/io/trajectory_io.h"

namespace ddl::eval {

struct AteOptions {
  double max_difference_s = 0.02;  // association window |t_gt - (t_est + offset)| < this
  double offset_s = 0.0;           // added to the estimate's stamps before association
  double scale = 1.0;              // multiplies the estimate's positions before alignment
  bool align_scale = false;        // false: Horn (the script); true: Umeyama with scale

  /// Throws ddl::ConfigError naming the option (max_difference_s > 0, scale > 0, all finite).
  void validate() const;
};

struct AteResult {
  std::size_t gt_poses = 0;   // poses in the ground-truth file
  std::size_t est_poses = 0;  // poses in the estimate file
  /// Associated pairs, sorted by ground-truth stamp (associate.py's order).
  std::vector<double> stamps_gt_s;
  std::vector<double> stamps_est_s;
  Eigen::Matrix3Xd gt_xyz;           // ground-truth positions of the pairs
  Eigen::Matrix3Xd est_xyz_aligned;  // aligned estimated positions of the pairs
  std::vector<double> errors_m;      // per pair |gt - aligned estimate|
  ErrorStats stats_m;                // statistics of errors_m
  Alignment alignment;               // estimate world -> ground-truth world
  /// Every estimated pose (times `scale`) mapped by `alignment`, in stamp order, for plots
  /// (the script's second_xyz_full_aligned).
  std::vector<double> est_all_stamps_s;
  Eigen::Matrix3Xd est_all_xyz_aligned;
};

/// Throws ddl::InputError when fewer than 2 poses associate (the message gives the count and the
/// association window; callers add the file names).
AteResult compute_ate(const io::Trajectory& gt, const io::Trajectory& est,
                      const AteOptions& options = {});

}  // namespace ddl::eval
