#include "ddl/eval/ate.h"

#include <fmt/format.h>

#include <cmath>

#include "ddl/core/error.h"
#include "ddl/io/associate.h"

namespace ddl::eval {

void AteOptions::validate() const {
  if (!std::isfinite(max_difference_s) || max_difference_s <= 0.0) {
    throw ConfigError::for_key("max_difference",
                               fmt::format("must be > 0 seconds, got {}", max_difference_s));
  }
  if (!std::isfinite(offset_s)) throw ConfigError::for_key("offset", "must be finite");
  if (!std::isfinite(scale) || scale <= 0.0) {
    throw ConfigError::for_key("scale", fmt::format("must be > 0, got {}", scale));
  }
}

AteResult compute_ate(const io::Trajectory& gt, const io::Trajectory& est,
                      const AteOptions& options) {
  options.validate();
  std::vector<double> gt_stamps(gt.size());
  std::vector<double> est_stamps(est.size());
  for (std::size_t i = 0; i < gt.size(); ++i) gt_stamps[i] = gt[i].timestamp_s;
  for (std::size_t i = 0; i < est.size(); ++i) est_stamps[i] = est[i].timestamp_s;

  const std::vector<io::StampMatch> matches =
      io::associate(gt_stamps, est_stamps, options.offset_s, options.max_difference_s);
  if (matches.size() < 2) {
    throw InputError(fmt::format(
        "only {} ground-truth/estimate pose(s) associate with |t_gt - (t_est + {} s)| < {} s "
        "(need at least 2): do the files belong to the same sequence and clock?",
        matches.size(), options.offset_s, options.max_difference_s));
  }

  AteResult r;
  r.gt_poses = gt.size();
  r.est_poses = est.size();
  const auto n = static_cast<Eigen::Index>(matches.size());
  r.gt_xyz.resize(3, n);
  Eigen::Matrix3Xd est_xyz(3, n);
  r.stamps_gt_s.reserve(matches.size());
  r.stamps_est_s.reserve(matches.size());
  for (Eigen::Index k = 0; k < n; ++k) {
    const io::StampMatch& m = matches[static_cast<std::size_t>(k)];
    r.stamps_gt_s.push_back(gt[m.first].timestamp_s);
    r.stamps_est_s.push_back(est[m.second].timestamp_s);
    r.gt_xyz.col(k) = gt[m.first].t_w_c;
    est_xyz.col(k) = est[m.second].t_w_c * options.scale;
  }

  if (options.align_scale && (est_xyz.colwise() - est_xyz.rowwise().mean()).squaredNorm() <= 0.0) {
    // The estimate's input fault (a tracker that never moved), not the library's: evaluate()
    // names both files for an InputError.
    throw InputError(
        "every matched estimate position is the same point: the scale of the "
        "alignment (--align-scale) is undefined");
  }
  r.alignment = options.align_scale ? align_umeyama(est_xyz, r.gt_xyz, /*with_scale=*/true)
                                    : align_horn(est_xyz, r.gt_xyz);
  r.est_xyz_aligned = r.alignment.apply(est_xyz);
  r.errors_m.resize(matches.size());
  for (Eigen::Index k = 0; k < n; ++k) {
    r.errors_m[static_cast<std::size_t>(k)] = (r.est_xyz_aligned.col(k) - r.gt_xyz.col(k)).norm();
  }
  r.stats_m = compute_stats(r.errors_m);

  r.est_all_stamps_s = est_stamps;
  Eigen::Matrix3Xd est_all(3, static_cast<Eigen::Index>(est.size()));
  for (std::size_t i = 0; i < est.size(); ++i) {
    est_all.col(static_cast<Eigen::Index>(i)) = est[i].t_w_c * options.scale;
  }
  r.est_all_xyz_aligned = r.alignment.apply(est_all);
  return r;
}

}  // namespace ddl::eval
