#include "ddl/eval/evaluate.h"

#include <fmt/format.h>

#include <cmath>

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
    r.rpe = compute_rpe(groundtruth, estimate, options.rpe());
    // Coordinates so large that the squared errors overflow (a diverged estimate written out,
    // or a file in other units) give no number a table could show.
    for (const double v : {r.ate.stats_m.rmse, r.rpe.trans_m.rmse, r.rpe.rot_deg.rmse}) {
      if (!std::isfinite(v)) {
        throw InputError(
            "the errors are not finite: coordinates too large to evaluate (in metres?)");
      }
    }
  } catch (const InputError& e) {
    throw both(e);
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
  }
  return r;
}

}  // namespace ddl::eval
