#include "ddl/optimization/pose_optimization.h"

#include <ceres/problem.h>
#include <ceres/solver.h>
#include <fmt/format.h>

#include <cmath>
#include <cstdint>

#include "ddl/core/error.h"
#include "ddl/optimization/cost_functions.h"
#include "ddl/optimization/se3_manifold.h"
#include "ddl/optimization/solver_support.h"

namespace ddl::optimization {
namespace {

/// ORB-SLAM2 gives up below 3 correspondences and runs a single round below 10.
constexpr std::size_t kMinObservations = 3;
constexpr std::size_t kMinObservationsForRounds = 10;

}  // namespace

PoseOptimizationResult optimize_pose(const CameraIntrinsics& camera, const SE3& T_c_w_initial,
                                     std::span<const PoseObservation> observations,
                                     const OptimizerConfig& config, const PosePrior* prior) {
  camera.validate();
  config.validate();
  const std::size_t n = observations.size();
  for (std::size_t i = 0; i < n; ++i) {
    detail::check_measurement(camera, observations[i].measurement, "pose observation", i);
    if (!observations[i].p_w.allFinite()) {
      throw Error(fmt::format("pose observation {}: map point is not finite", i));
    }
  }

  PoseOptimizationResult result;
  result.T_c_w = T_c_w_initial;
  result.inliers.assign(n, false);
  if (n < kMinObservations) return result;

  PoseParameters x = to_parameters(T_c_w_initial);
  std::vector<std::uint8_t> active(n, 1);
  bool robust = true;
  detail::SwitchableHuberLoss mono_loss(std::sqrt(config.chi2_mono), &robust);
  detail::SwitchableHuberLoss stereo_loss(std::sqrt(config.chi2_stereo), &robust);
  SE3Manifold manifold;

  ceres::Problem::Options problem_options;
  problem_options.loss_function_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem problem(problem_options);
  problem.AddParameterBlock(x.data(), kPoseAmbientSize, &manifold);
  for (std::size_t i = 0; i < n; ++i) {
    const PoseObservation& obs = observations[i];
    if (obs.measurement.stereo) {
      problem.AddResidualBlock(
          new PoseReprojectionCost<3>(camera, obs.p_w, obs.measurement, &active[i]), &stereo_loss,
          x.data());
    } else {
      problem.AddResidualBlock(
          new PoseReprojectionCost<2>(camera, obs.p_w, obs.measurement, &active[i]), &mono_loss,
          x.data());
    }
  }

  if (prior != nullptr) {
    if (!prior->sqrt_information.allFinite()) throw Error("pose prior: information is not finite");
    problem.AddResidualBlock(new PosePriorCost(prior->T_c_w, prior->sqrt_information), nullptr,
                             x.data());
  }

  ceres::Solver::Options options =
      detail::base_options(config.num_threads, config.pose_iterations_per_round);
  // One 6-dof block: the normal equations are 6x6.
  options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;

  for (int round = 0; round < config.pose_rounds; ++round) {
    robust = round < config.pose_robust_rounds;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    detail::solution_usable(summary, "pose optimisation");
    result.iterations += detail::iterations_run(summary);

    const SE3 T_c_w = from_parameters(x.data());
    result.num_inliers = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const Measurement& m = observations[i].measurement;
      double depth_m = 0.0;
      const double chi2 = reprojection_chi2(camera, T_c_w, observations[i].p_w, m, &depth_m);
      const bool inlier =
          depth_m > 0.0 && chi2 <= (m.stereo ? config.chi2_stereo : config.chi2_mono);
      active[i] = inlier ? 1 : 0;
      result.inliers[i] = inlier;
      result.num_inliers += inlier ? 1 : 0;
    }
    if (n < kMinObservationsForRounds) break;
  }
  result.T_c_w = from_parameters(x.data());
  result.optimized = true;
  return result;
}

}  // namespace ddl::optimization
