#pragma once
// The paper's result tables (DDL-SLAM, Tables 1-3) from the summaries of paired runs: for each
// sequence one run with dynamic-content removal ("ours") and one of the plain SLAM core (the
// paper's "ORB-SLAM2" column, `--no-dynamic`). Used by `ddl_slam bench`; docs/evaluation.md
// documents the files.
//
//   Table 1  ATE (m)                       RMSE, mean, median, S.D. of both columns + improvement
//   Table 2  RPE translational (m/s)       same
//   Table 3  RPE rotational (deg/s)        same
//   masks    IoU / precision / recall of the CNN, geometry and combined masks ("ours" run)
//   tracking frames processed and tracked, tracked ratio, wall time of both runs
// improvement = (baseline - ours) / baseline * 100, the paper's definition (positive = better).

#include <nlohmann/json.hpp>
#include <string>
#include <vector>

namespace ddl::eval {

struct BenchmarkRow {
  std::string sequence;
  nlohmann::json ours;      // summary.json of the run with dynamic removal (null: not run)
  nlohmann::json baseline;  // summary.json of the --no-dynamic run (null: not run)
};

/// (baseline - ours) / baseline * 100; NaN when either is not finite or baseline is 0.
double improvement_percent(double baseline, double ours);

/// tables.json: {settings, columns, sequences, ate, rpe_translation, rpe_rotation, masks,
/// tracking, skipped}. `settings` and `skipped` (array of {sequence, reason}) are copied in.
nlohmann::json benchmark_tables(const std::vector<BenchmarkRow>& rows,
                                const nlohmann::json& settings, const nlohmann::json& skipped);

/// tables.md: the same tables as Markdown (errors with at least 4 decimals and 3 significant
/// digits, mask scores with 3 decimals, "-" for none).
std::string benchmark_tables_markdown(const nlohmann::json& tables);

}  // namespace ddl::eval
