#pragma once
// Bundle adjustment of keyframe poses and map points over reprojection residuals (mono (u, v) or
// RGB-D (u, v, u_right), see cost_functions.h) with Huber kernels of width sqrt(chi2 threshold):
//   - local BA (local mapping, ORB-SLAM2 Optimizer::LocalBundleAdjustment): the caller passes
//     the local keyframes (free), the keyframes that also see the local points (fixed=true), the
//     local points and all their observations; schedule OptimizerConfig::local_ba (5 robust
//     iterations, drop chi2 / negative-depth outliers and the kernels, 10 more);
//   - global BA (after a loop closure, ORB-SLAM2 GlobalBundleAdjustemnt): every keyframe and
//     point; keyframes[0] is always held fixed (the gauge) besides those marked fixed; schedule
//     OptimizerConfig::global_ba (10 robust iterations, no outlier pass).
// Points are eliminated with the Schur complement (DENSE_SCHUR for few free poses, else
// SPARSE_SCHUR with the best sparse library Ceres has; OptimizerConfig::ba_linear_solver).
// A SolveControl::abort flag stops the solve after the current iteration (the refinement phase is
// then skipped); the estimate reached so far is returned with aborted = true.
//
// Thread-safety: pure functions of their arguments; the abort flag may be set from any thread.

#include <cstddef>
#include <string>
#include <vector>

#include "ddl/core/se3.h"
#include "ddl/optimization/optimizer_config.h"
#include "ddl/optimization/types.h"

namespace ddl::optimization {

struct BaKeyframe {
  SE3 T_c_w;           ///< world -> camera
  bool fixed = false;  ///< held constant (returned bit-exactly)
};

struct BaObservation {
  std::size_t keyframe = 0;  ///< index into BundleAdjustmentProblem::keyframes
  std::size_t point = 0;     ///< index into BundleAdjustmentProblem::points_w
  Measurement measurement;
};

struct BundleAdjustmentProblem {
  CameraIntrinsics camera;  ///< shared by every keyframe
  std::vector<BaKeyframe> keyframes;
  std::vector<Vec3d> points_w;  ///< map points in world coordinates [m]
  std::vector<BaObservation> observations;
};

struct BundleAdjustmentResult {
  std::vector<SE3> T_c_w;  ///< per keyframe; fixed ones and ones without observations unchanged
  std::vector<Vec3d> points_w;  ///< per point; points without observations unchanged
  /// Indices into problem.observations that are outliers at the returned estimate (chi2 above
  /// the threshold of their dof, or the point not in front of the camera). After a local BA the
  /// caller erases these keyframe-point associations from the map (ORB-SLAM2's vToErase).
  std::vector<std::size_t> outliers;
  bool aborted = false;       ///< the abort flag stopped the optimisation
  bool failed = false;        ///< Ceres returned no usable solution (logged; no outliers given)
  int iterations = 0;         ///< LM iterations over all phases
  double initial_cost = 0.0;  ///< Ceres cost (0.5 sum of robustified chi2) before the first phase
  double final_cost = 0.0;    ///< Ceres cost after the last phase that ran
  std::string linear_solver;  ///< the Ceres linear solver used, for logs
};

/// Runs `schedule` on `problem`; keyframes with fixed=true (and, when fix_first_keyframe, the
/// first keyframe with observations: keyframes[0] unless it has none) are held constant. Throws
/// ddl::Error naming the observation when an index is out of range or a value is unusable,
/// ddl::ConfigError when camera or config are invalid.
BundleAdjustmentResult bundle_adjustment(const BundleAdjustmentProblem& problem,
                                         const BundleAdjustmentSchedule& schedule,
                                         bool fix_first_keyframe, const OptimizerConfig& config,
                                         const SolveControl& control = {});

/// bundle_adjustment(problem, config.local_ba, false, config, control).
BundleAdjustmentResult local_bundle_adjustment(const BundleAdjustmentProblem& problem,
                                               const OptimizerConfig& config,
                                               const SolveControl& control = {});

/// bundle_adjustment(problem, config.global_ba, true, config, control).
BundleAdjustmentResult global_bundle_adjustment(const BundleAdjustmentProblem& problem,
                                                const OptimizerConfig& config,
                                                const SolveControl& control = {});

}  // namespace ddl::optimization
