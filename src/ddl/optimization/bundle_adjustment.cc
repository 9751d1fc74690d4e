#include "ddl/optimization/bundle_adjustment.h"

#include <ceres/ordered_groups.h>
#include <ceres/problem.h>
#include <ceres/solver.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cmath>
#include <cstdint>
#include <memory>

#include "ddl/core/error.h"
#include "ddl/optimization/cost_functions.h"
#include "ddl/optimization/se3_manifold.h"
#include "ddl/optimization/solver_support.h"

namespace ddl::optimization {
namespace {

void check_problem(const BundleAdjustmentProblem& problem) {
  for (std::size_t k = 0; k < problem.keyframes.size(); ++k) {
    const SE3& T = problem.keyframes[k].T_c_w;
    if (!T.quaternion().coeffs().allFinite() || !T.translation().allFinite()) {
      throw Error(fmt::format("bundle adjustment keyframe {}: pose is not finite", k));
    }
  }
  for (std::size_t p = 0; p < problem.points_w.size(); ++p) {
    if (!problem.points_w[p].allFinite()) {
      throw Error(fmt::format("bundle adjustment point {}: position is not finite", p));
    }
  }
  for (std::size_t i = 0; i < problem.observations.size(); ++i) {
    const BaObservation& obs = problem.observations[i];
    if (obs.keyframe >= problem.keyframes.size()) {
      throw Error(
          fmt::format("bundle adjustment observation {}: keyframe index {} out of range "
                      "(problem has {} keyframes)",
                      i, obs.keyframe, problem.keyframes.size()));
    }
    if (obs.point >= problem.points_w.size()) {
      throw Error(
          fmt::format("bundle adjustment observation {}: point index {} out of range "
                      "(problem has {} points)",
                      i, obs.point, problem.points_w.size()));
    }
    detail::check_measurement(problem.camera, obs.measurement, "bundle adjustment observation", i);
  }
}

/// Picks the linear solver; returns its name for the result.
std::string configure_linear_solver(const OptimizerConfig& config, int free_poses,
                                    ceres::Solver::Options* options) {
  const auto sparse = detail::best_sparse_library();
  if (free_poses == 0) {
    // Only points move: the normal equations are block diagonal, no Schur complement to form.
    if (sparse) {
      options->linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
      options->sparse_linear_algebra_library_type = *sparse;
    } else {
      options->linear_solver_type = ceres::CGNR;
    }
    options->linear_solver_ordering.reset();
    return ceres::LinearSolverTypeToString(options->linear_solver_type);
  }
  BaLinearSolver choice = config.ba_linear_solver;
  if (choice == BaLinearSolver::kAuto) {
    choice = free_poses <= config.dense_schur_max_poses ? BaLinearSolver::kDenseSchur
                                                        : BaLinearSolver::kSparseSchur;
  }
  if (choice == BaLinearSolver::kSparseSchur && !sparse) choice = BaLinearSolver::kIterativeSchur;
  switch (choice) {
    case BaLinearSolver::kDenseSchur:
      options->linear_solver_type = ceres::DENSE_SCHUR;
      break;
    case BaLinearSolver::kSparseSchur:
      options->linear_solver_type = ceres::SPARSE_SCHUR;
      options->sparse_linear_algebra_library_type = *sparse;
      break;
    default:
      options->linear_solver_type = ceres::ITERATIVE_SCHUR;
      options->preconditioner_type = ceres::SCHUR_JACOBI;
      break;
  }
  return ceres::LinearSolverTypeToString(options->linear_solver_type);
}

}  // namespace

BundleAdjustmentResult bundle_adjustment(const BundleAdjustmentProblem& problem,
                                         const BundleAdjustmentSchedule& schedule,
                                         bool fix_first_keyframe, const OptimizerConfig& config,
                                         const SolveControl& control) {
  problem.camera.validate();
  config.validate();
  check_problem(problem);

  const std::size_t num_kf = problem.keyframes.size();
  const std::size_t num_pt = problem.points_w.size();
  const std::size_t num_obs = problem.observations.size();
  BundleAdjustmentResult result;
  result.T_c_w.reserve(num_kf);
  for (const BaKeyframe& kf : problem.keyframes) result.T_c_w.push_back(kf.T_c_w);
  result.points_w = problem.points_w;
  if (num_obs == 0) return result;

  std::vector<PoseParameters> poses(num_kf);
  for (std::size_t k = 0; k < num_kf; ++k) poses[k] = to_parameters(problem.keyframes[k].T_c_w);
  std::vector<Vec3d> points = problem.points_w;
  std::vector<std::uint8_t> kf_used(num_kf, 0);
  std::vector<int> point_active_count(num_pt, 0);
  for (const BaObservation& obs : problem.observations) {
    kf_used[obs.keyframe] = 1;
    ++point_active_count[obs.point];
  }
  // The gauge: the first keyframe that takes part (keyframes[0] unless it observes nothing, when
  // holding it would leave the problem's gauge free).
  const std::size_t gauge = static_cast<std::size_t>(
      std::find(kf_used.begin(), kf_used.end(), std::uint8_t{1}) - kf_used.begin());
  auto is_fixed = [&](std::size_t k) {
    return problem.keyframes[k].fixed || (fix_first_keyframe && k == gauge);
  };

  std::vector<std::uint8_t> active(num_obs, 1);
  bool robust = true;
  detail::SwitchableHuberLoss mono_loss(std::sqrt(config.chi2_mono), &robust);
  detail::SwitchableHuberLoss stereo_loss(std::sqrt(config.chi2_stereo), &robust);
  SE3Manifold manifold;

  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem ceres_problem(problem_options);
  auto ordering = std::make_shared<ceres::ParameterBlockOrdering>();
  int free_poses = 0;
  for (std::size_t k = 0; k < num_kf; ++k) {
    if (kf_used[k] == 0) continue;
    ceres_problem.AddParameterBlock(poses[k].data(), kPoseAmbientSize, &manifold);
    if (is_fixed(k)) {
      ceres_problem.SetParameterBlockConstant(poses[k].data());
    } else {
      ++free_poses;
    }
    ordering->AddElementToGroup(poses[k].data(), 1);
  }
  for (std::size_t p = 0; p < num_pt; ++p) {
    if (point_active_count[p] == 0) continue;
    ceres_problem.AddParameterBlock(points[p].data(), 3);
    ordering->AddElementToGroup(points[p].data(), 0);
  }
  for (std::size_t i = 0; i < num_obs; ++i) {
    const BaObservation& obs = problem.observations[i];
    double* pose = poses[obs.keyframe].data();
    double* point = points[obs.point].data();
    if (obs.measurement.stereo) {
      ceres_problem.AddResidualBlock(
          new BaReprojectionCost<3>(problem.camera, obs.measurement, &active[i]), &stereo_loss,
          pose, point);
    } else {
      ceres_problem.AddResidualBlock(
          new BaReprojectionCost<2>(problem.camera, obs.measurement, &active[i]), &mono_loss, pose,
          point);
    }
  }

  ceres::Solver::Options options =
      detail::base_options(config.num_threads, schedule.initial_iterations);
  // Ceres edits the ordering it is given (it removes the constant blocks), so each solve gets
  // its own copy of the one built here.
  const ceres::ParameterBlockOrdering elimination_order = *ordering;
  options.linear_solver_ordering = ordering;
  result.linear_solver = configure_linear_solver(config, free_poses, &options);
  detail::ControlCallback callback(control);
  options.callbacks.push_back(&callback);

  // A local copy of the classification: returns whether observation i is an outlier now.
  auto is_outlier = [&](std::size_t i) {
    const BaObservation& obs = problem.observations[i];
    double depth_m = 0.0;
    const double chi2 =
        reprojection_chi2(problem.camera, from_parameters(poses[obs.keyframe].data()),
                          points[obs.point], obs.measurement, &depth_m);
    return depth_m <= 0.0 ||
           chi2 > (obs.measurement.stereo ? config.chi2_stereo : config.chi2_mono);
  };

  ceres::Solver::Summary summary;
  ceres::Solve(options, &ceres_problem, &summary);
  result.failed = !detail::solution_usable(summary, "bundle adjustment");
  result.initial_cost = summary.initial_cost;
  result.final_cost = summary.final_cost;
  result.iterations = detail::iterations_run(summary);
  const bool robust_phase_completed = !callback.aborted();

  if (robust_phase_completed && !result.failed && schedule.remove_outliers) {
    for (std::size_t i = 0; i < num_obs; ++i) {
      if (!is_outlier(i)) continue;
      active[i] = 0;
      --point_active_count[problem.observations[i].point];
    }
    // A point left without observations has nothing to pin it: hold it where it is.
    for (std::size_t p = 0; p < num_pt; ++p) {
      if (point_active_count[p] == 0 && ceres_problem.HasParameterBlock(points[p].data())) {
        ceres_problem.SetParameterBlockConstant(points[p].data());
      }
    }
    robust = false;
    if (schedule.refine_iterations > 0) {
      options.max_num_iterations = schedule.refine_iterations;
      if (options.linear_solver_ordering) {
        options.linear_solver_ordering =
            std::make_shared<ceres::ParameterBlockOrdering>(elimination_order);
      }
      ceres::Solve(options, &ceres_problem, &summary);
      result.failed = !detail::solution_usable(summary, "bundle adjustment (refinement)");
      result.final_cost = summary.final_cost;
      result.iterations += detail::iterations_run(summary);
    }
  }
  result.aborted = callback.aborted();

  // Aborted during its robust phase, the solve judged nothing: chi2 at the input estimate, or
  // after a few of the robust iterations, is no outlier test. ORB-SLAM2 tests anyway; after a
  // loop correction, whose residuals only BA removes, the first local BA is usually aborted
  // (tracking queues keyframes right after the pause, while mapping is busy) and its test then
  // erased half of the map's observations (review, threaded composite: 16 642 of 31 598 after 1
  // iteration). A failed solve (either phase) gives no outliers either: its caller keeps the map as
  // it was, the first phase's estimate included.
  const bool judged = robust_phase_completed && !result.failed;
  for (std::size_t i = 0; judged && i < num_obs; ++i) {
    if (is_outlier(i)) result.outliers.push_back(i);
  }
  for (std::size_t k = 0; k < num_kf; ++k) {
    if (kf_used[k] != 0 && !is_fixed(k)) result.T_c_w[k] = from_parameters(poses[k].data());
  }
  for (std::size_t p = 0; p < num_pt; ++p) result.points_w[p] = points[p];
  spdlog::debug(
      "bundle adjustment: {} keyframes ({} free), {} observations, {} iterations, {}, cost {:.4g} "
      "-> {:.4g}, {} outliers{}",
      num_kf, free_poses, num_obs, result.iterations, result.linear_solver, result.initial_cost,
      result.final_cost, result.outliers.size(), result.aborted ? ", aborted" : "");
  return result;
}

BundleAdjustmentResult local_bundle_adjustment(const BundleAdjustmentProblem& problem,
                                               const OptimizerConfig& config,
                                               const SolveControl& control) {
  return bundle_adjustment(problem, config.local_ba, false, config, control);
}

BundleAdjustmentResult global_bundle_adjustment(const BundleAdjustmentProblem& problem,
                                                const OptimizerConfig& config,
                                                const SolveControl& control) {
  return bundle_adjustment(problem, config.global_ba, true, config, control);
}

}  // namespace ddl::optimization
