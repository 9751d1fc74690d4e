#include "ddl/eval/evaluate.h"

#include <fmt/format.h>

#include <cmath>
#include <vector>

#include "ddl/core/error.h"

namespace ddl::eval {

AteOptions EvalOptions::ate() const {
  AteOptions o;
  o.max_difference_s = max_difference_s;
  o.offset_s = offset_s;
  o.scale = scale;
  o.align_scale = align_scale;
  return o;
}

RpeOptions EvalOptions::rpe() const {
  RpeOptions o;
  o.delta = rpe_delta;
  o.delta_unit = rpe_delta_unit;
  o.offset_s = offset_s;
  o.scale = scale;
  return o;
}

void EvalOptions::validate() const {
  ate().validate();
  rpe().validate();
}

EvalResult evaluate(const io::Trajectory& groundtruth, const io::Trajectory& estimate,
                    const EvalOptions& options, const std::string& groundtruth_name,
                    const std::string& estimate_name) {
  options.validate();
  EvalResult r;
  r.inputs.groundtruth_path = groundtruth_name;
  r.inputs.estimate_path = estimate_name;
  r.options = options;
  r.groundtruth = groundtruth;
  r.estimate = estimate;
  // Overlap problems concern both files: name them.
  const auto both = [&](const InputError& e) {
    return InputError(fmt::format("{} (estimate) vs {} (ground truth): {}", estimate_name,
                                  groundtruth_name, e.what()));
  };
  try {
    r.ate = compute_ate(groundtruth, estimate, options.ate());
  } catch (const InputError& e) {
    throw both(e);
  }
  // As the TUM scripts, which are two programs: an estimate too short for RPE's delta still has
  // its ATE (evaluate_ate.py succeeds where evaluate_rpe.py fails).
  try {
    r.rpe = compute_rpe(groundtruth, estimate, options.rpe());
  } catch (const InputError& e) {
    r.rpe = RpeResult{};
    r.rpe_error = both(e).what();
  }
  // Coordinates so large that the squared errors overflow (a diverged estimate written out, or a
  // file in other units) give no number a table could show.
  std::vector<double> errors = {r.ate.stats_m.rmse};
  if (r.rpe_error.empty()) errors.insert(errors.end(), {r.rpe.trans_m.rmse, r.rpe.rot_deg.rmse});
  for (const double v : errors) {
    if (!std::isfinite(v)) {
      throw both(
          InputError("the errors are not finite: coordinates too large to evaluate (in metres?)"));
    }
  }
  return r;
}

EvalResult evaluate(const EvalInputs& inputs, const EvalOptions& options) {
  options.validate();
  const io::Trajectory gt = io::read_tum_trajectory(inputs.groundtruth_path);
  const io::Trajectory est = io::read_tum_trajectory(inputs.estimate_path);
  std::optional<std::vector<double>> frames;
  if (!inputs.frames_path.empty()) frames = read_frame_stamps(inputs.frames_path);
  EvalResult r = evaluate(gt, est, options, inputs.groundtruth_path, inputs.estimate_path);
  r.inputs = inputs;
  if (frames) {
    r.tracked = compute_tracked(*frames, gt, est, options.offset_s, options.max_difference_s);
    if (r.tracked->frames_in_gt_span == 0) {
      throw InputError::at(
          inputs.frames_path,
          fmt::format("none of its {} frames lies inside the ground truth's time span [{:.6f}, "
                      "{:.6f}] (with --offset {} s): is it the frame list of this sequence?",
                      r.tracked->frames_total, gt.front().timestamp_s, gt.back().timestamp_s,
                      options.offset_s));
    }
  }
  return r;
}

}  // namespace ddl::eval
