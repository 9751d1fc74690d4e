#pragma once
// Settings of every optimisation problem in ddl::optimization. Defaults reproduce ORB-SLAM2's
// g2o schedules (Optimizer::PoseOptimization, LocalBundleAdjustment, GlobalBundleAdjustemnt,
// OptimizeEssentialGraph) with Ceres doing the solving.

#include <string>

namespace ddl::optimization {

/// Which linear solver the bundle adjustments use for their Schur-complement system.
enum class BaLinearSolver {
  kAuto,            ///< DENSE_SCHUR up to dense_schur_max_poses free poses, else SPARSE_SCHUR
  kDenseSchur,      ///< ceres::DENSE_SCHUR
  kSparseSchur,     ///< ceres::SPARSE_SCHUR (falls back to ITERATIVE_SCHUR without a sparse lib)
  kIterativeSchur,  ///< ceres::ITERATIVE_SCHUR with the SCHUR_JACOBI preconditioner
};

/// Iteration schedule of a bundle adjustment: `initial_iterations` Levenberg-Marquardt iterations
/// with Huber kernels on every observation, then (when remove_outliers) the observations whose
/// chi2 exceeds the threshold or whose point lies behind the camera are dropped, the kernels are
/// switched off and `refine_iterations` more iterations run.
struct BundleAdjustmentSchedule {
  int initial_iterations = 5;   ///< LM iterations of the robust phase (>= 1)
  bool remove_outliers = true;  ///< run the outlier pass and the refinement phase
  int refine_iterations = 10;   ///< LM iterations after outlier removal (>= 0)
};

struct OptimizerConfig {
  /// Threads Ceres may use for evaluation and linear algebra (1 = single-threaded, the default:
  /// the pipeline runs tracking, mapping and loop closing on their own threads already).
  int num_threads = 1;

  /// Chi-square outlier thresholds at 95% (2 dof: monocular (u, v); 3 dof: RGB-D (u, v, u_right)).
  /// The Huber kernel widths are their square roots, as in ORB-SLAM2.
  double chi2_mono = 5.991;
  double chi2_stereo = 7.815;

  /// Pose-only (motion-only) BA: rounds of LM, each followed by a chi2 inlier classification
  /// (outliers sit out the next round but are re-classified after it).
  int pose_rounds = 4;
  int pose_iterations_per_round = 10;  ///< LM iterations per round
  int pose_robust_rounds = 3;          ///< the first N rounds use Huber kernels, later ones none

  /// Local BA (local mapping) and global BA (after a loop closure) schedules.
  BundleAdjustmentSchedule local_ba{5, true, 10};
  BundleAdjustmentSchedule global_ba{10, false, 0};
  BaLinearSolver ba_linear_solver = BaLinearSolver::kAuto;
  int dense_schur_max_poses = 60;  ///< kAuto: DENSE_SCHUR while free poses <= this

  /// Pose graph optimisation over SE(3) (essential graph after a loop closure).
  int pose_graph_iterations = 20;

  /// Throws ddl::ConfigError naming the key (optimizer.<field>) of the first invalid value.
  void validate() const;
};

/// "auto", "dense_schur", "sparse_schur", "iterative_schur".
std::string to_string(BaLinearSolver solver);
/// Inverse of to_string; throws ddl::ConfigError for key optimizer.ba_linear_solver otherwise.
BaLinearSolver ba_linear_solver_from_string(const std::string& name);

}  // namespace ddl::optimization
