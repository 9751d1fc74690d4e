#include "ddl/eval/report.h"

#include <fmt/format.h>

#include <cmath>

#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"

namespace ddl::eval {
namespace {

using nlohmann::json;

// NaN and infinity have no JSON form: write null.
json number(double v) { return std::isfinite(v) ? json(v) : json(nullptr); }

std::string ate_method(const EvalOptions& o) {
  return fmt::format(
      "TUM evaluate_ate.py: associate |dt|<{} s, offset {} s, scale {}, {} alignment, "
      "translational error statistics",
      o.max_difference_s, o.offset_s, o.scale,
      o.align_scale ? "Umeyama with scale (not in the script)" : "Horn without scale");
}

std::string rpe_method(const EvalOptions& o) {
  return fmt::format(
      "TUM evaluate_rpe.py --fixed_delta --delta {} --delta_unit {} --offset {} --scale {} "
      "(pairs matched to nearest ground-truth stamps), all pairs (no random subsampling above "
      "10000), translational (m per delta) and rotational (deg per delta) error",
      o.rpe_delta, to_string(o.rpe_delta_unit), o.offset_s, o.scale);
}

std::string per_delta_unit(const EvalOptions& o) {
  if (o.rpe_delta_unit == DeltaUnit::kSeconds) {
    return o.rpe_delta == 1.0 ? "s" : fmt::format("{} s", o.rpe_delta);
  }
  return o.rpe_delta == 1.0 ? "frame" : fmt::format("{} frames", o.rpe_delta);
}

}  // namespace

std::string format_report(const EvalResult& r) {
  const EvalOptions& o = r.options;
  std::string s;
  s += fmt::format("ground truth : {} ({} poses)\n", r.inputs.groundtruth_path, r.ate.gt_poses);
  s += fmt::format("estimate     : {} ({} poses)\n\n", r.inputs.estimate_path, r.ate.est_poses);

  s += fmt::format("ATE  ({} alignment, |dt| < {} s, offset {} s, scale {})\n",
                   o.align_scale ? "Umeyama+scale" : "Horn", o.max_difference_s, o.offset_s,
                   o.scale);
  s += fmt::format("  {:<22}{:>12}\n", "estimated poses", r.ate.est_poses);
  s += fmt::format("  {:<22}{:>12}\n", "compared pose pairs", r.ate.stats_m.count);
  const auto ate_row = [&](const char* name, double v) {
    s += fmt::format("  {:<22}{:>12.6f} m\n", name, v);
  };
  ate_row("rmse", r.ate.stats_m.rmse);
  ate_row("mean", r.ate.stats_m.mean);
  ate_row("median", r.ate.stats_m.median);
  ate_row("std", r.ate.stats_m.std);
  ate_row("min", r.ate.stats_m.min);
  ate_row("max", r.ate.stats_m.max);

  const std::string per = per_delta_unit(o);
  s += fmt::format("\nRPE  (fixed delta {} {}, all pairs)\n", o.rpe_delta,
                   to_string(o.rpe_delta_unit));
  const auto rpe_row = [&](const char* name, double t, double rot) {
    s += fmt::format("  {:<10}{:>24.6f}{:>24.6f}\n", name, t, rot);
  };
  if (!r.rpe_error.empty()) {
    s += fmt::format("  unavailable: {}\n", r.rpe_error);
  } else {
    s += fmt::format("  {:<22}{:>12}\n", "compared pose pairs", r.rpe.trans_m.count);
    s += fmt::format("  {:<10}{:>24}{:>24}\n", "", fmt::format("translation [m/{}]", per),
                     fmt::format("rotation [deg/{}]", per));
    rpe_row("rmse", r.rpe.trans_m.rmse, r.rpe.rot_deg.rmse);
    rpe_row("mean", r.rpe.trans_m.mean, r.rpe.rot_deg.mean);
    rpe_row("median", r.rpe.trans_m.median, r.rpe.rot_deg.median);
    rpe_row("std", r.rpe.trans_m.std, r.rpe.rot_deg.std);
    rpe_row("min", r.rpe.trans_m.min, r.rpe.rot_deg.min);
    rpe_row("max", r.rpe.trans_m.max, r.rpe.rot_deg.max);
  }

  s += "\nTracked\n";
  if (r.tracked) {
    const TrackedStats& t = *r.tracked;
    s += fmt::format("  {} of {} frames inside the ground-truth span have a pose ({:.1f} %)\n",
                     t.tracked_frames, t.frames_in_gt_span, 100.0 * t.ratio);
    s += fmt::format("  frames file: {} ({} frames)\n", r.inputs.frames_path, t.frames_total);
  } else {
    s += "  unavailable (give --frames rgb.txt or associations.txt)\n";
  }

  const Alignment& a = r.ate.alignment;
  s += "\nAlignment (p_gt = scale * R * p_est + t)\n";
  s += fmt::format("  scale        {:.9f}\n", a.scale);
  for (int i = 0; i < 3; ++i) {
    s += fmt::format("  {}[{:>12.9f} {:>12.9f} {:>12.9f}]   t {:>12.6f}\n",
                     i == 0 ? "R          " : "           ", a.R_gt_est(i, 0), a.R_gt_est(i, 1),
                     a.R_gt_est(i, 2), a.t_gt_est(i));
  }
  return s;
}

json to_json(const EvalResult& r) {
  const EvalOptions& o = r.options;
  json j;
  const ErrorStats& a = r.ate.stats_m;
  j["ate"] = {{"est_poses", r.ate.est_poses},   {"gt_poses", r.ate.gt_poses},
              {"compared_pose_pairs", a.count}, {"rmse_m", number(a.rmse)},
              {"mean_m", number(a.mean)},       {"median_m", number(a.median)},
              {"std_m", number(a.std)},         {"min_m", number(a.min)},
              {"max_m", number(a.max)}};

  const ErrorStats& t = r.rpe.trans_m;
  const ErrorStats& q = r.rpe.rot_deg;
  const bool seconds = o.rpe_delta_unit == DeltaUnit::kSeconds;
  const bool rpe = r.rpe_error.empty();
  // Unavailable (an estimate shorter than the delta): every statistic null, never a zero that
  // looks measured; a table shows "-".
  const auto stat = [&](double v) { return rpe ? number(v) : json(nullptr); };
  j["rpe"] = {{"available", rpe},
              {"error", rpe ? json(nullptr) : json(r.rpe_error)},
              {"delta", o.rpe_delta},
              {"delta_unit", to_string(o.rpe_delta_unit)},
              {"delta_s", seconds ? json(o.rpe_delta) : json(nullptr)},
              {"compared_pose_pairs", rpe ? json(t.count) : json(nullptr)},
              {"trans_rmse_m_per_s", stat(t.rmse)},
              {"trans_mean_m_per_s", stat(t.mean)},
              {"trans_median_m_per_s", stat(t.median)},
              {"trans_std_m_per_s", stat(t.std)},
              {"trans_min_m_per_s", stat(t.min)},
              {"trans_max_m_per_s", stat(t.max)},
              {"rot_rmse_deg_per_s", stat(q.rmse)},
              {"rot_mean_deg_per_s", stat(q.mean)},
              {"rot_median_deg_per_s", stat(q.median)},
              {"rot_std_deg_per_s", stat(q.std)},
              {"rot_min_deg_per_s", stat(q.min)},
              {"rot_max_deg_per_s", stat(q.max)}};

  if (r.tracked) {
    const TrackedStats& k = *r.tracked;
    j["tracked"] = {{"available", true},
                    {"frames_file", r.inputs.frames_path},
                    {"frames_total", k.frames_total},
                    {"frames_in_gt_span", k.frames_in_gt_span},
                    {"tracked_frames", k.tracked_frames},
                    {"est_poses", r.ate.est_poses},
                    {"ratio", number(k.ratio)}};
  } else {
    j["tracked"] = {{"available", false},        {"frames_file", nullptr},
                    {"frames_total", nullptr},   {"frames_in_gt_span", nullptr},
                    {"tracked_frames", nullptr}, {"est_poses", r.ate.est_poses},
                    {"ratio", nullptr}};
  }

  const Alignment& al = r.ate.alignment;
  json rotation = json::array();
  for (int i = 0; i < 3; ++i) {
    rotation.push_back({al.R_gt_est(i, 0), al.R_gt_est(i, 1), al.R_gt_est(i, 2)});
  }
  j["alignment"] = {{"method", o.align_scale ? "umeyama_scale" : "horn"},
                    {"rotation", rotation},
                    {"translation", {al.t_gt_est.x(), al.t_gt_est.y(), al.t_gt_est.z()}},
                    {"scale", al.scale},
                    {"estimate_scale_factor", o.scale}};

  j["inputs"] = {
      {"groundtruth", r.inputs.groundtruth_path},
      {"estimate", r.inputs.estimate_path},
      {"frames", r.inputs.frames_path.empty() ? json(nullptr) : json(r.inputs.frames_path)}};
  j["method"] = {{"ate", ate_method(o)}, {"rpe", rpe_method(o)}};
  return j;
}

void write_json_report(const std::string& path, const EvalResult& result) {
  write_file_atomically(path, "the evaluation report",
                        to_json(result).dump(1, ' ', false, json::error_handler_t::replace) + '\n');
}

}  // namespace ddl::eval
