#pragma once
// Relative pose error exactly as the TUM RGB-D benchmark's
// `evaluate_rpe.py --fixed_delta --delta D --delta_unit s|f` (defaults D = 1, unit s):
//  - poses whose quaternion is exactly (0, 0, 0, 0) are dropped (NaN lines are already dropped by
//    io::read_tum_trajectory); each pose becomes a 4x4 matrix by the script's transform44
//    (q scaled by sqrt(2 / |q|^2), rotation from the outer product q q^T);
//  - for every estimated pose i, j = find_closest_index(index, index[i] + D) where index is the
//    sorted estimate stamps (unit s) or 0..n-1 (unit f); the pair (i, j) is kept only when j is not
//    the last index (the script drops those pairs, and so does this);
//  - both estimated stamps (plus offset) are matched to their nearest ground-truth stamps; the pair
//    is skipped if either is further than 2 * median(ground-truth stamp interval);
//  - E = ominus(scale(ominus(est_1, est_0), s), ominus(gt_1, gt_0)) with ominus(a, b) = a^-1 b,
//    translational error |E.t|, rotational error arccos(clamp((trace(E.R) - 1) / 2, -1, 1)).
// One deliberate difference: the script randomly subsamples 10000 pairs when there are more
// (--max_pairs); this uses every pair, so results are deterministic.
// Errors are per delta interval: with the default D = 1 s, metres per second and degrees per
// second.

#include <cstddef>
#include <string>
#include <vector>

#include "ddl/core/types.h"
#include "ddl/eval/stats.h"
#include "ddl/io/trajectory_io.h"

namespace ddl::eval {

enum class DeltaUnit { kSeconds, kFrames };

/// "s" or "f"; throws ddl::ConfigError naming key "delta_unit" otherwise.
DeltaUnit parse_delta_unit(const std::string& text);
std::string to_string(DeltaUnit unit);

struct RpeOptions {
  double delta = 1.0;  // distance between the poses of a pair, in delta_unit
  DeltaUnit delta_unit = DeltaUnit::kSeconds;  // seconds or frames (estimate indices)
  double offset_s = 0.0;  // added to the estimate's stamps to find ground truth
  double scale = 1.0;     // multiplies the estimate's relative translations

  /// Throws ddl::ConfigError naming the option (delta > 0, scale > 0, all finite).
  void validate() const;
};

struct RpePair {
  double stamp_est_0_s = 0.0;
  double stamp_est_1_s = 0.0;
  double stamp_gt_0_s = 0.0;
  double stamp_gt_1_s = 0.0;
  double trans_error_m = 0.0;
  double rot_error_rad = 0.0;
};

struct RpeResult {
  RpeOptions options;
  std::size_t est_poses_used = 0;         // estimate poses after dropping zero quaternions
  std::size_t est_zero_quaternions = 0;   // estimate poses dropped for a zero quaternion
  std::size_t candidate_pairs = 0;        // pairs (i, j) before the ground-truth time check
  double gt_max_time_difference_s = 0.0;  // 2 * median ground-truth interval
  std::vector<RpePair> pairs;             // compared pairs, in the order of i
  ErrorStats trans_m;                     // translational error, metres per delta
  ErrorStats rot_deg;                     // rotational error, degrees per delta
};

/// Throws ddl::InputError when the stamps overlap in fewer than 2 poses or fewer than 2 pairs can
/// be compared (the script's two exceptions; callers add the file names).
RpeResult compute_rpe(const io::Trajectory& gt, const io::Trajectory& est,
                      const RpeOptions& options = {});

/// The script's transform44: 4x4 matrix of a pose from its raw (not necessarily unit) quaternion.
Mat4d tum_transform44(const io::StampedPose& pose);

/// The script's find_closest_index on a sorted list: a binary search that remembers the element
/// with the smallest |L[k] - t| seen on its path (earliest wins ties) and returns at once on an
/// exact hit. Precondition: `sorted` is not empty.
std::size_t find_closest_index(const std::vector<double>& sorted, double t);

}  // namespace ddl::eval
