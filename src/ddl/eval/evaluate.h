#pragma once
// One evaluation of an estimated trajectory file against a ground-truth file: reads both (and an
// optional frame list), computes ATE, RPE and the tracked ratio. This is what `ddl_slam eval` and
// the pipeline's end-of-run evaluation call; errors name the files involved.

#include <optional>
#include <string>

#include "ddl/eval/ate.h"
#include "ddl/eval/rpe.h"
#include "ddl/eval/tracked.h"
#include "ddl/io/trajectory_io.h"

namespace ddl::eval {

struct EvalInputs {
  std::string groundtruth_path;  // TUM trajectory (groundtruth.txt)
  std::string estimate_path;     // TUM trajectory written by the SLAM run
  std::string frames_path;       // optional: rgb.txt or associations.txt; empty = no tracked ratio
};

struct EvalOptions {
  double max_difference_s = 0.02;  // ATE association window (evaluate_ate.py --max_difference)
  double offset_s = 0.0;           // added to estimate stamps (both scripts' --offset)
  double scale = 1.0;              // estimate scale factor (both scripts' --scale)
  bool align_scale = false;        // ATE: Umeyama with scale instead of Horn
  double rpe_delta = 1.0;          // evaluate_rpe.py --delta
  DeltaUnit rpe_delta_unit = DeltaUnit::kSeconds;  // evaluate_rpe.py --delta_unit (s or f)

  AteOptions ate() const;
  RpeOptions rpe() const;
  /// Throws ddl::ConfigError naming the bad option.
  void validate() const;
};

struct EvalResult {
  EvalInputs inputs;
  EvalOptions options;
  io::Trajectory groundtruth;
  io::Trajectory estimate;
  AteResult ate;
  RpeResult rpe;          // empty when rpe_error is set
  std::string rpe_error;  // why RPE could not be computed (too short for the delta); ATE still is
  std::optional<TrackedStats> tracked;  // set when inputs.frames_path is given
};

/// Throws ddl::InputError naming the file (and line) for unreadable or malformed input, and naming
/// both trajectory files when they do not overlap in time.
EvalResult evaluate(const EvalInputs& inputs, const EvalOptions& options = {});

/// The same on trajectories already in memory (names are used in error messages only).
EvalResult evaluate(const io::Trajectory& groundtruth, const io::Trajectory& estimate,
                    const EvalOptions& options, const std::string& groundtruth_name,
                    const std::string& estimate_name);

}  // namespace ddl::eval
