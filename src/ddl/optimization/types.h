#pragma once
// Plain input types shared by the optimisation problems. They carry no reference to the map
// (ARCHITECTURE.md section 2: optimisation depends on core only), so tracking, local mapping and
// loop closing copy what they need into these structs, call a problem, and write results back.
//
// Conventions used by every problem in this module:
//   - poses are T_c_w (world -> camera) unless a field says otherwise;
//   - pixels are undistorted (the pinhole model below has no distortion);
//   - an RGB-D keypoint carries a virtual right-image coordinate u_right = u - bf / depth
//     (ORB-SLAM2's RGB-D convention), which gives the 3-dof "stereo" residual (u, v, u_right).

#include <atomic>
#include <functional>

#include "ddl/core/types.h"

namespace ddl::optimization {

/// Rectified pinhole camera with a (virtual) stereo baseline.
struct CameraIntrinsics {
  double fx = 0.0;  ///< focal length x [px]
  double fy = 0.0;  ///< focal length y [px]
  double cx = 0.0;  ///< principal point x [px]
  double cy = 0.0;  ///< principal point y [px]
  /// Baseline [m] times fx [px]: u_right = u - bf / z. Only stereo residuals use it.
  double bf = 0.0;

  /// Throws ddl::ConfigError naming the key (camera.fx, ...) when a value is not usable.
  void validate() const;
};

/// One keypoint measurement of a 3D point.
struct Measurement {
  Vec2d uv_px = Vec2d::Zero();  ///< undistorted keypoint in the (left / RGB) image [px]
  double u_right_px = 0.0;      ///< virtual right-image column [px]; read only when stereo
  bool stereo = false;          ///< true: residual (u, v, u_right), 3 dof; false: (u, v), 2 dof
  double inv_sigma2 = 1.0;      ///< 1 / sigma^2 of the keypoint's pyramid level (information)
};

/// Optional run-time control of the longer problems (local/global BA, pose graph).
struct SolveControl {
  SolveControl() = default;
  /// Only an abort flag: local_bundle_adjustment(problem, config, SolveControl(&flag)).
  explicit SolveControl(const std::atomic<bool>* abort_flag) : abort(abort_flag) {}

  /// When non-null, read (acquire) by a Ceres iteration callback after every iteration; once it
  /// reads true the solver stops and keeps the last accepted estimate. Any thread may set it.
  const std::atomic<bool>* abort = nullptr;
  /// When set, called on the optimising thread after every Ceres iteration with the iteration
  /// index inside the current solve (0 = initial evaluation) and the current cost. Diagnostics and
  /// tests only; it must be cheap.
  std::function<void(int iteration, double cost)> on_iteration;
};

}  // namespace ddl::optimization
