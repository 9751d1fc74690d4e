#pragma once
// Internal helpers shared by the problems of this module (not part of the public API).

#include <ceres/iteration_callback.h>
#include <ceres/loss_function.h>
#include <ceres/solver.h>

#include <cstddef>
#include <optional>

#include "ddl/optimization/types.h"

namespace ddl::optimization::detail {

/// Iteration callback that forwards to SolveControl::on_iteration and stops the solve once the
/// abort flag reads true (SOLVER_TERMINATE_SUCCESSFULLY: the last accepted estimate is kept).
class ControlCallback final : public ceres::IterationCallback {
 public:
  explicit ControlCallback(const SolveControl& control) : control_(control) {}
  ceres::CallbackReturnType operator()(const ceres::IterationSummary& summary) override;
  bool aborted() const { return aborted_; }
  bool abort_requested() const;

 private:
  const SolveControl& control_;
  bool aborted_ = false;
};

/// Huber kernel rho(s) = s for s <= delta^2, 2 delta sqrt(s) - delta^2 beyond (g2o's and Ceres'
/// HuberLoss on the squared whitened residual s = chi2) that turns into the identity while
/// *enabled is false, so a problem can drop its kernels between solves without being rebuilt.
class SwitchableHuberLoss final : public ceres::LossFunction {
 public:
  SwitchableHuberLoss(double delta, const bool* enabled)
      : delta_(delta), delta2_(delta * delta), enabled_(enabled) {}
  void Evaluate(double s, double rho[3]) const override;

 private:
  double delta_;
  double delta2_;
  const bool* enabled_;
};

/// The best sparse linear algebra library this Ceres build has (SuiteSparse, then Eigen's sparse
/// Cholesky, then CXSparse); nullopt when it was built without any.
std::optional<ceres::SparseLinearAlgebraLibraryType> best_sparse_library();

/// Throws ddl::Error naming `what` and `index` when a measurement cannot be used.
void check_measurement(const CameraIntrinsics& camera, const Measurement& m, const char* what,
                       std::size_t index);

/// Iterations a solve ran (Ceres records iteration 0, the initial evaluation, as well).
int iterations_run(const ceres::Solver::Summary& summary);
/// Whether Ceres left a usable solution (not FAILURE / USER_FAILURE); logs a warning with
/// Ceres' message, naming `what`, when it did not.
bool solution_usable(const ceres::Solver::Summary& summary, const char* what);

/// Options every problem shares: silent, given thread count, at most max_iterations iterations.
ceres::Solver::Options base_options(int num_threads, int max_iterations);

}  // namespace ddl::optimization::detail
