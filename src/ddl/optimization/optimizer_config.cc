#include "ddl/optimization/optimizer_config.h"

#include <fmt/format.h>

#include <cmath>

#include "ddl/core/error.h"
#include "ddl/optimization/types.h"

namespace ddl::optimization {
namespace {

void require(bool ok, const std::string& key, const std::string& what) {
  if (!ok) throw ConfigError::for_key(key, what);
}

void require_int_range(int value, int lo, int hi, const std::string& key) {
  require(value >= lo && value <= hi, key,
          fmt::format("must be in {}..{} (got {})", lo, hi, value));
}

void validate_schedule(const BundleAdjustmentSchedule& s, const std::string& prefix) {
  require_int_range(s.initial_iterations, 1, 1000, prefix + ".initial_iterations");
  require_int_range(s.refine_iterations, 0, 1000, prefix + ".refine_iterations");
}

}  // namespace

void CameraIntrinsics::validate() const {
  auto positive = [](double v, const char* key) {
    require(std::isfinite(v) && v > 0.0, key, fmt::format("must be a positive number (got {})", v));
  };
  positive(fx, "camera.fx");
  positive(fy, "camera.fy");
  require(std::isfinite(cx), "camera.cx", fmt::format("must be finite (got {})", cx));
  require(std::isfinite(cy), "camera.cy", fmt::format("must be finite (got {})", cy));
  require(std::isfinite(bf) && bf >= 0.0, "camera.bf",
          fmt::format("must be >= 0 (baseline in metres times fx; got {})", bf));
}

void OptimizerConfig::validate() const {
  require_int_range(num_threads, 1, 256, "optimizer.num_threads");
  require(std::isfinite(chi2_mono) && chi2_mono > 0.0, "optimizer.chi2_mono",
          fmt::format("must be a positive chi-square threshold (got {})", chi2_mono));
  require(std::isfinite(chi2_stereo) && chi2_stereo > 0.0, "optimizer.chi2_stereo",
          fmt::format("must be a positive chi-square threshold (got {})", chi2_stereo));
  require_int_range(pose_rounds, 1, 100, "optimizer.pose_rounds");
  require_int_range(pose_iterations_per_round, 1, 1000, "optimizer.pose_iterations_per_round");
  require_int_range(pose_robust_rounds, 0, 100, "optimizer.pose_robust_rounds");
  validate_schedule(local_ba, "optimizer.local_ba");
  validate_schedule(global_ba, "optimizer.global_ba");
  require_int_range(dense_schur_max_poses, 0, 100000, "optimizer.dense_schur_max_poses");
  require_int_range(pose_graph_iterations, 1, 10000, "optimizer.pose_graph_iterations");
}

std::string to_string(BaLinearSolver solver) {
  switch (solver) {
    case BaLinearSolver::kAuto:
      return "auto";
    case BaLinearSolver::kDenseSchur:
      return "dense_schur";
    case BaLinearSolver::kSparseSchur:
      return "sparse_schur";
    case BaLinearSolver::kIterativeSchur:
      return "iterative_schur";
  }
  return "auto";
}

BaLinearSolver ba_linear_solver_from_string(const std::string& name) {
  for (BaLinearSolver s : {BaLinearSolver::kAuto, BaLinearSolver::kDenseSchur,
                           BaLinearSolver::kSparseSchur, BaLinearSolver::kIterativeSchur}) {
    if (to_string(s) == name) return s;
  }
  throw ConfigError::for_key(
      "optimizer.ba_linear_solver",
      fmt::format("unknown solver '{}' (expected auto, dense_schur, sparse_schur or "
                  "iterative_schur)",
                  name));
}

}  // namespace ddl::optimization
