#pragma once
// Motion-only bundle adjustment of a tracking frame (ORB-SLAM2 Optimizer::PoseOptimization via
// ddl::optimization::optimize_pose): the frame's matched map points are fixed, the pose is
// optimised, and every match is classified inlier / outlier by its chi2 (3 dof with depth,
// 2 dof without).
// One estimator per tracking thread (it reuses its buffers).

#include <cstddef>
#include <vector>

#include "ddl/optimization/optimizer_config.h"
#include "ddl/optimization/pose_optimization.h"
#include "ddl/tracking/frame.h"

namespace ddl::tracking {

/// optimize() is virtual so that a test can steer a caller's control flow (relocalization); the
/// tracker uses this class as it is.
class FramePoseEstimator {
 public:
  FramePoseEstimator(const FrameGeometry& geometry, const optimization::OptimizerConfig& config);
  virtual ~FramePoseEstimator() = default;

  /// Optimises frame.T_c_w() (the initial guess) against the frame's matched points and sets
  /// the outlier flags of all matches. Returns the number of inliers (0 and nothing changed
  /// with fewer than 3 matches).
  virtual int optimize(Frame& frame);
  /// The same with a Gaussian prior on the pose (the motion model's prediction).
  int optimize_with_prior(Frame& frame, const optimization::PosePrior& prior);

 private:
  int run(Frame& frame, const optimization::PosePrior* prior);

  optimization::CameraIntrinsics intrinsics_;
  optimization::OptimizerConfig config_;
  std::vector<optimization::PoseObservation> observations_;
  std::vector<std::size_t> slots_;
};

/// Removes the matches flagged as outliers from the frame (remembering them as rejected for this
/// frame). Returns the number of remaining matches whose map point has observations.
int discard_outliers(Frame& frame);

}  // namespace ddl::tracking
