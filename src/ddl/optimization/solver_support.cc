#include "ddl/optimization/solver_support.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "ddl/core/error.h"

namespace ddl::optimization::detail {

void SwitchableHuberLoss::Evaluate(double s, double rho[3]) const {
  if (!*enabled_ || s <= delta2_) {
    rho[0] = s;
    rho[1] = 1.0;
    rho[2] = 0.0;
    return;
  }
  const double r = std::sqrt(s);
  rho[0] = 2.0 * delta_ * r - delta2_;
  rho[1] = std::max(std::numeric_limits<double>::min(), delta_ / r);
  rho[2] = -rho[1] / (2.0 * s);
}

ceres::CallbackReturnType ControlCallback::operator()(const ceres::IterationSummary& summary) {
  if (control_.on_iteration) control_.on_iteration(summary.iteration, summary.cost);
  if (abort_requested()) {
    aborted_ = true;
    return ceres::SOLVER_TERMINATE_SUCCESSFULLY;
  }
  return ceres::SOLVER_CONTINUE;
}

bool ControlCallback::abort_requested() const {
  return control_.abort != nullptr && control_.abort->load(std::memory_order_acquire);
}

void check_measurement(const CameraIntrinsics& camera, const Measurement& m, const char* what,
                       std::size_t index) {
  const char* problem = nullptr;
  if (!m.uv_px.allFinite()) {
    problem = "keypoint is not finite";
  } else if (!std::isfinite(m.inv_sigma2) || m.inv_sigma2 <= 0.0) {
    problem = "inv_sigma2 must be a positive number";
  } else if (m.stereo && !std::isfinite(m.u_right_px)) {
    problem = "u_right_px is not finite";
  } else if (m.stereo && camera.bf <= 0.0) {
    problem = "stereo measurement needs camera.bf > 0";
  }
  if (problem != nullptr) throw Error(fmt::format("{} {}: {}", what, index, problem));
}

std::optional<ceres::SparseLinearAlgebraLibraryType> best_sparse_library() {
  for (ceres::SparseLinearAlgebraLibraryType type :
       {ceres::SUITE_SPARSE, ceres::EIGEN_SPARSE, ceres::CX_SPARSE}) {
    if (ceres::IsSparseLinearAlgebraLibraryTypeAvailable(type)) return type;
  }
  return std::nullopt;
}

int iterations_run(const ceres::Solver::Summary& summary) {
  return summary.iterations.empty() ? 0 : static_cast<int>(summary.iterations.size()) - 1;
}

bool solution_usable(const ceres::Solver::Summary& summary, const char* what) {
  if (summary.IsSolutionUsable()) return true;
  spdlog::warn("{}: Ceres failed ({}): {}", what,
               ceres::TerminationTypeToString(summary.termination_type), summary.message);
  return false;
}

ceres::Solver::Options base_options(int num_threads, int max_iterations) {
  ceres::Solver::Options options;
  options.minimizer_type = ceres::TRUST_REGION;
  options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
  options.max_num_iterations = max_iterations;
  options.num_threads = num_threads;
  options.logging_type = ceres::SILENT;
  options.minimizer_progress_to_stdout = false;
  return options;
}

}  // namespace ddl::optimization::detail
