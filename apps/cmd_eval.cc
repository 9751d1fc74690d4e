// `ddl_slam eval`: ATE / RPE (TUM-exact), tracked ratio, JSON report and plots.

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "cli_support.h"
#include "commands.h"
#include "ddl/eval/evaluate.h"
#include "ddl/eval/plot.h"
#include "ddl/eval/report.h"

namespace ddl::app {
namespace {

struct EvalArgs {
  eval::EvalInputs inputs;
  eval::EvalOptions options;
  std::string delta_unit = "s";
  std::string json_path;
  std::string plot_dir;
  std::string plane = "xy";
};

int run_eval(const EvalArgs& args) {
  eval::EvalOptions options = args.options;
  options.rpe_delta_unit = eval::parse_delta_unit(args.delta_unit);
  const eval::Plane plane = eval::parse_plane(args.plane);
  const eval::EvalResult result = eval::evaluate(args.inputs, options);
  std::fputs(eval::format_report(result).c_str(), stdout);
  std::fflush(stdout);
  if (!result.rpe_error.empty()) spdlog::warn("RPE unavailable: {}", result.rpe_error);
  if (!args.json_path.empty()) {
    eval::write_json_report(args.json_path, result);
    spdlog::info("wrote {}", args.json_path);
  }
  if (!args.plot_dir.empty()) {
    for (const std::string& path : eval::write_eval_plots(result, args.plot_dir, plane)) {
      spdlog::info("wrote {}", path);
    }
  }
  return kOk;
}

}  // namespace

void add_eval_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<EvalArgs>();
  CLI::App* cmd = app.add_subcommand(
      "eval",
      "Evaluate an estimated camera trajectory against ground truth, exactly as the TUM RGB-D "
      "benchmark scripts do: ATE (evaluate_ate.py defaults: association |dt| < 0.02 s, Horn "
      "alignment without scale) and RPE (evaluate_rpe.py --fixed_delta --delta 1 --delta_unit s, "
      "but over all pairs, never randomly subsampled). Also reports the tracked ratio (--frames), "
      "writes a JSON report (--json) and PNG+SVG plots (--plot-dir). Both files are TUM "
      "trajectories: 'timestamp tx ty tz qx qy qz qw' per line. See docs/evaluation.md.");
  cmd->add_option("--gt", args->inputs.groundtruth_path,
                  "Ground-truth trajectory, e.g. <sequence>/groundtruth.txt")
      ->required();
  cmd->add_option("--est", args->inputs.estimate_path,
                  "Estimated trajectory (TUM format) to evaluate")
      ->required();
  cmd->add_option("--frames", args->inputs.frames_path,
                  "Frame list (TUM rgb.txt or associations.txt; first column = frame stamp) for "
                  "the tracked ratio: frames inside the ground-truth time span that have a pose. "
                  "Without it the ratio is reported as unavailable");
  cmd->add_option("--json", args->json_path, "Write the results as JSON to this file");
  cmd->add_option("--plot-dir", args->plot_dir,
                  "Write plots here (PNG and SVG): trajectory top view with ATE differences, ATE "
                  "over time, RPE over time");
  cmd->add_option("--plane", args->plane, "Plane of the trajectory plot: xy, xz or yz")
      ->check(CLI::IsMember({"xy", "xz", "yz"}))
      ->capture_default_str();
  cmd->add_option("--max-difference", args->options.max_difference_s,
                  "ATE: maximal |t_gt - (t_est + offset)| in seconds for associated poses")
      ->capture_default_str();
  cmd->add_option("--offset", args->options.offset_s,
                  "Time offset in seconds added to the estimate's stamps (ATE and RPE)")
      ->capture_default_str();
  cmd->add_option("--scale", args->options.scale,
                  "Multiply the estimate's translations by this factor before evaluation (as the "
                  "scripts' --scale)")
      ->capture_default_str();
  cmd->add_flag("--align-scale", args->options.align_scale,
                "ATE: align with Umeyama's method including a scale factor (for monocular "
                "estimates) instead of the script's rigid Horn alignment");
  cmd->add_option("--delta", args->options.rpe_delta,
                  "RPE: distance between the two poses of a pair, in --delta-unit")
      ->capture_default_str();
  cmd->add_option("--delta-unit", args->delta_unit,
                  "RPE: unit of --delta: s (seconds) or f (frames of the estimate)")
      ->check(CLI::IsMember({"s", "f"}))
      ->capture_default_str();
  cmd->callback([args, &exit_code] { exit_code = run_guarded([&] { return run_eval(*args); }); });
}

}  // namespace ddl::app
