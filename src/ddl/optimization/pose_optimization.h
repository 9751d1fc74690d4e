#pragma once
// Pose-only (motion-only) bundle adjustment: the camera pose T_c_w of one frame against fixed map
// points, as ORB-SLAM2's Optimizer::PoseOptimization for RGB-D. Called by tracking for every
// frame (motion model, reference keyframe, local map, relocalization), so it is built for speed:
// analytic Jacobians, one ceres::Problem reused over all rounds.
//
// Schedule (OptimizerConfig): pose_rounds rounds of pose_iterations_per_round Levenberg-Marquardt
// iterations. After each round every observation is classified at the current pose: inlier when
// its point is in front of the camera and chi2 <= chi2_mono (2 dof) / chi2_stereo (3 dof).
// Outliers sit out the next round but are classified again after it. The first
// pose_robust_rounds rounds use Huber kernels of width sqrt(chi2 threshold); later rounds none.
// With fewer than 10 observations only one round runs (ORB-SLAM2), with fewer than 3 none.
//
// Thread-safety: a pure function of its arguments; any thread may call it.

#include <span>
#include <vector>

#include "ddl/core/se3.h"
#include "ddl/optimization/optimizer_config.h"
#include "ddl/optimization/types.h"

namespace ddl::optimization {

/// A fixed map point and its keypoint in the frame being optimised.
struct PoseObservation {
  Vec3d p_w = Vec3d::Zero();  ///< map point in world coordinates [m]; not optimised
  Measurement measurement;
};

/// A Gaussian prior on the pose (e.g. the motion model's prediction): the cost
/// |L^T log(T_c_w * T_c_w_prior^-1)|^2 joins the reprojection residuals in every round, with no
/// robust kernel. sqrt_information = L^T of the information matrix ([rho; phi] order).
struct PosePrior {
  SE3 T_c_w;
  Mat6d sqrt_information = Mat6d::Identity();
};

struct PoseOptimizationResult {
  SE3 T_c_w;                  ///< optimised pose (the initial pose when !optimized)
  std::vector<bool> inliers;  ///< per observation: inlier after the last round's classification
  int num_inliers = 0;        ///< count of true in inliers (0 when !optimized)
  bool optimized = false;     ///< false: fewer than 3 observations, nothing was done
  int iterations = 0;         ///< LM iterations run over all rounds
};

/// Optimises T_c_w (world -> camera) starting from T_c_w_initial. Throws ddl::Error when an
/// observation is malformed (non-finite values, inv_sigma2 <= 0, stereo with camera.bf == 0) or
/// ddl::ConfigError when camera or config do not validate.
PoseOptimizationResult optimize_pose(const CameraIntrinsics& camera, const SE3& T_c_w_initial,
                                     std::span<const PoseObservation> observations,
                                     const OptimizerConfig& config,
                                     const PosePrior* prior = nullptr);

}  // namespace ddl::optimization
