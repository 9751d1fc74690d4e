#include "ddl/eval/rpe.h"

#include <fmt/format.h>

#include <Eigen/LU>
#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "ddl/core/error.h"

namespace ddl::eval {
namespace {

// ominus(a, b) = inv(a) * b (general 4x4 inverse, as numpy.linalg.inv).
Mat4d ominus(const Mat4d& a, const Mat4d& b) { return a.inverse() * b; }

}  // namespace

DeltaUnit parse_delta_unit(const std::string& text) {
  if (text == "s") return DeltaUnit::kSeconds;
  if (text == "f") return DeltaUnit::kFrames;
  throw ConfigError::for_key(
      "delta_unit", fmt::format("'{}' is not a unit: use 's' (seconds) or 'f' (frames)", text));
}

std::string to_string(DeltaUnit unit) { return unit == DeltaUnit::kSeconds ? "s" : "f"; }

void RpeOptions::validate() const {
  if (!std::isfinite(delta) || delta <= 0.0) {
    throw ConfigError::for_key("delta", fmt::format("must be > 0, got {}", delta));
  }
  if (!std::isfinite(offset_s)) throw ConfigError::for_key("offset", "must be finite");
  if (!std::isfinite(scale) || scale <= 0.0) {
    throw ConfigError::for_key("scale", fmt::format("must be > 0, got {}", scale));
  }
}

Mat4d tum_transform44(const io::StampedPose& pose) {
  Mat4d T = Mat4d::Identity();
  T.block<3, 1>(0, 3) = pose.t_w_c;
  Vec4d q = pose.q_xyzw;  // (x, y, z, w) as in the file
  const double nq = q.dot(q);
  // The script's branch for |q|^2 < 4 eps is meant to give an identity rotation (as written it
  // raises); zero quaternions never get here because they are dropped first.
  if (nq < 4.0 * std::numeric_limits<double>::epsilon()) return T;
  q *= std::sqrt(2.0 / nq);
  const Mat4d o = q * q.transpose();
  T(0, 0) = 1.0 - o(1, 1) - o(2, 2);
  T(0, 1) = o(0, 1) - o(2, 3);
  T(0, 2) = o(0, 2) + o(1, 3);
  T(1, 0) = o(0, 1) + o(2, 3);
  T(1, 1) = 1.0 - o(0, 0) - o(2, 2);
  T(1, 2) = o(1, 2) - o(0, 3);
  T(2, 0) = o(0, 2) - o(1, 3);
  T(2, 1) = o(1, 2) + o(0, 3);
  T(2, 2) = 1.0 - o(0, 0) - o(1, 1);
  return T;
}

std::size_t find_closest_index(const std::vector<double>& sorted, double t) {
  std::size_t beginning = 0;
  double difference = std::abs(sorted[0] - t);
  std::size_t best = 0;
  std::size_t end = sorted.size();
  while (beginning < end) {
    const std::size_t middle = (end + beginning) / 2;
    if (std::abs(sorted[middle] - t) < difference) {
      difference = std::abs(sorted[middle] - t);
      best = middle;
    }
    if (t == sorted[middle]) return middle;
    if (sorted[middle] > t) {
      end = middle;
    } else {
      beginning = middle + 1;
    }
  }
  return best;
}

RpeResult compute_rpe(const io::Trajectory& gt_in, const io::Trajectory& est_in,
                      const RpeOptions& options) {
  options.validate();
  RpeResult r;
  r.options = options;

  // read_trajectory: drop poses whose quaternion is exactly [0, 0, 0, 0].
  const auto keep = [](const io::StampedPose& p) { return !(p.q_xyzw.array() == 0.0).all(); };
  std::vector<double> stamps_gt;
  std::vector<double> stamps_est;
  std::vector<Mat4d> traj_gt;
  std::vector<Mat4d> traj_est;
  for (const io::StampedPose& p : gt_in) {
    if (!keep(p)) continue;
    stamps_gt.push_back(p.timestamp_s);
    traj_gt.push_back(tum_transform44(p));
  }
  for (const io::StampedPose& p : est_in) {
    if (!keep(p)) {
      ++r.est_zero_quaternions;
      continue;
    }
    stamps_est.push_back(p.timestamp_s);
    traj_est.push_back(tum_transform44(p));
  }
  r.est_poses_used = stamps_est.size();
  // io::read_tum_trajectory guarantees strictly increasing stamps, so these lists are the
  // script's sorted dictionary keys.

  // The script's overlap check: distinct estimate stamps reached by a round trip through the
  // nearest ground-truth stamp.
  std::size_t overlap = 0;
  if (!stamps_gt.empty() && !stamps_est.empty()) {
    std::vector<bool> returned(stamps_est.size(), false);  // stamps are distinct: mark indices
    for (double t_est : stamps_est) {
      const double t_gt = stamps_gt[find_closest_index(stamps_gt, t_est + options.offset_s)];
      const std::size_t back = find_closest_index(stamps_est, t_gt - options.offset_s);
      if (!returned[back]) {
        returned[back] = true;
        ++overlap;
      }
    }
  }
  if (overlap < 2) {
    throw InputError(fmt::format(
        "RPE: the stamps of ground truth ({} usable poses) and estimate ({} usable poses) overlap "
        "in only {} pose(s) (need at least 2): are the files from the same sequence?",
        stamps_gt.size(), stamps_est.size(), overlap));
  }

  std::vector<double> index_est;
  if (options.delta_unit == DeltaUnit::kSeconds) {
    index_est = stamps_est;
  } else {
    index_est.resize(stamps_est.size());
    for (std::size_t i = 0; i < index_est.size(); ++i) index_est[i] = static_cast<double>(i);
  }

  std::vector<std::pair<std::size_t, std::size_t>> pairs;
  const std::size_t last = stamps_est.size() - 1;
  for (std::size_t i = 0; i < stamps_est.size(); ++i) {
    const std::size_t j = find_closest_index(index_est, index_est[i] + options.delta);
    if (j != last) pairs.emplace_back(i, j);
  }
  r.candidate_pairs = pairs.size();

  std::vector<double> gt_intervals;
  gt_intervals.reserve(stamps_gt.size() - 1);
  for (std::size_t k = 1; k < stamps_gt.size(); ++k) {
    gt_intervals.push_back(stamps_gt[k] - stamps_gt[k - 1]);
  }
  r.gt_max_time_difference_s = 2.0 * numpy_median(gt_intervals);

  std::vector<double> trans_errors;
  std::vector<double> rot_errors;
  for (const auto& [i, j] : pairs) {
    RpePair p;
    p.stamp_est_0_s = stamps_est[i];
    p.stamp_est_1_s = stamps_est[j];
    const std::size_t g0 = find_closest_index(stamps_gt, p.stamp_est_0_s + options.offset_s);
    const std::size_t g1 = find_closest_index(stamps_gt, p.stamp_est_1_s + options.offset_s);
    p.stamp_gt_0_s = stamps_gt[g0];
    p.stamp_gt_1_s = stamps_gt[g1];
    if (std::abs(p.stamp_gt_0_s - (p.stamp_est_0_s + options.offset_s)) >
            r.gt_max_time_difference_s ||
        std::abs(p.stamp_gt_1_s - (p.stamp_est_1_s + options.offset_s)) >
            r.gt_max_time_difference_s) {
      continue;
    }
    Mat4d est_rel = ominus(traj_est[j], traj_est[i]);
    est_rel.block<3, 1>(0, 3) *= options.scale;
    const Mat4d error44 = ominus(est_rel, ominus(traj_gt[g1], traj_gt[g0]));
    p.trans_error_m = error44.block<3, 1>(0, 3).norm();
    const double c = (error44.block<3, 3>(0, 0).trace() - 1.0) / 2.0;
    p.rot_error_rad = std::acos(std::min(1.0, std::max(-1.0, c)));
    trans_errors.push_back(p.trans_error_m);
    rot_errors.push_back(p.rot_error_rad);
    r.pairs.push_back(p);
  }
  if (r.pairs.size() < 2) {
    throw InputError(fmt::format(
        "RPE: only {} pose pair(s) {} {} apart have ground truth within {} s (need at least 2): is "
        "the estimate shorter than delta, or are the files from different sequences?",
        r.pairs.size(), options.delta, to_string(options.delta_unit), r.gt_max_time_difference_s));
  }
  r.trans_m = compute_stats(trans_errors);
  r.rot_deg = compute_stats(rot_errors).scaled(180.0 / std::numbers::pi);
  return r;
}

}  // namespace ddl::eval
