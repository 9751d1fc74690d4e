#pragma once
// Analytic Ceres cost functions of the module. Every pose parameter block is 7 ambient doubles on
// SE3Manifold (se3_manifold.h); the Jacobians are derived in the tangent space (left perturbation)
// and mapped to the ambient space with tangent_to_ambient, which Ceres multiplies back by
// PlusJacobian -- so what the solver sees is exactly the tangent Jacobian.
//
// Reprojection residuals (whitened by the information 1/sigma^2 of the keypoint's level):
//   mono   (N = 2): r = sqrt(inv_sigma2) * ([u, v] - [u_obs, v_obs])
//   stereo (N = 3): r = sqrt(inv_sigma2) * ([u, v, u - bf / z] - [u_obs, v_obs, u_right_obs])
//   with p_c = T_c_w * p_w = (x, y, z), u = fx x / z + cx, v = fy y / z + cy.
// so chi2 = |r|^2 is g2o's e^T Omega e with Omega = inv_sigma2 * I.

#include <ceres/sized_cost_function.h>

#include <cstdint>

#include "ddl/core/se3.h"
#include "ddl/optimization/se3_manifold.h"
#include "ddl/optimization/types.h"

namespace ddl::optimization {

/// Whitened reprojection of a camera-frame point for one measurement (N = 2 mono, 3 stereo).
template <int N>
class ReprojectionModel {
 public:
  using Residual = Eigen::Matrix<double, N, 1>;
  using PointJacobian = Eigen::Matrix<double, N, 3>;

  ReprojectionModel(const CameraIntrinsics& camera, const Measurement& measurement);

  /// Residual r (N) at the camera-frame point p_c and, when J is non-null, dr/dp_c (N x 3).
  /// A point on the camera plane (|z| < 1e-12) gives r = 0 and J = 0 (it carries no information);
  /// points behind the camera are projected like g2o does and caught by the depth checks of the
  /// outlier classification.
  void evaluate(const Vec3d& p_c, Residual* r, PointJacobian* J) const;

 private:
  double fx_, fy_, cx_, cy_, bf_;
  double sqrt_info_;
  Residual observed_;
};

/// Pose-only residual: the point p_w is data, the only parameter block is the pose T_c_w.
/// When `active` is non-null and *active == 0 the residual and Jacobian are zero: the
/// observation sits out the solve (an outlier of the previous round) without rebuilding the
/// ceres::Problem.
template <int N>
class PoseReprojectionCost final : public ceres::SizedCostFunction<N, kPoseAmbientSize> {
 public:
  PoseReprojectionCost(const CameraIntrinsics& camera, const Vec3d& p_w,
                       const Measurement& measurement, const std::uint8_t* active = nullptr)
      : model_(camera, measurement), p_w_(p_w), active_(active) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  ReprojectionModel<N> model_;
  Vec3d p_w_;
  const std::uint8_t* active_;
};

/// Bundle adjustment residual over the pose T_c_w (7) and the point p_w (3). `active` as above.
template <int N>
class BaReprojectionCost final : public ceres::SizedCostFunction<N, kPoseAmbientSize, 3> {
 public:
  BaReprojectionCost(const CameraIntrinsics& camera, const Measurement& measurement,
                     const std::uint8_t* active = nullptr)
      : model_(camera, measurement), active_(active) {}
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  ReprojectionModel<N> model_;
  const std::uint8_t* active_;
};

/// Relative-pose constraint between vertices i and j, both T_c_w:
///   e = log(T_i_j_measured^-1 * T_i_w * T_j_w^-1)   (twist [rho; phi], zero when consistent)
///   r = L^T e with L L^T = information (6x6, [rho; phi] order).
/// T_i_j maps camera-j coordinates into camera i (T_i_j = T_i_w * T_w_j).
class PoseGraphEdgeCost final
    : public ceres::SizedCostFunction<6, kPoseAmbientSize, kPoseAmbientSize> {
 public:
  /// sqrt_information = L^T (upper triangular) of the information matrix.
  PoseGraphEdgeCost(const SE3& T_i_j, const Mat6d& sqrt_information);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  SE3 T_j_i_measured_;  // inverse of the measurement
  Mat6d adjoint_T_j_i_;
  Mat6d sqrt_information_;
};

/// Unary prior on a pose T_c_w (a prediction of it, e.g. the constant-velocity motion model):
///   e = log(T_c_w * T_c_w_prior^-1)   (twist [rho; phi] in the camera frame, zero at the prior)
///   r = L^T e with L L^T = information (6x6, [rho; phi] order).
class PosePriorCost final : public ceres::SizedCostFunction<6, kPoseAmbientSize> {
 public:
  /// sqrt_information = L^T (upper triangular) of the information matrix.
  PosePriorCost(const SE3& T_c_w_prior, const Mat6d& sqrt_information);
  bool Evaluate(double const* const* parameters, double* residuals,
                double** jacobians) const override;

 private:
  SE3 T_w_c_prior_;  // inverse of the prior
  Mat6d sqrt_information_;
};

/// chi2 = inv_sigma2 * |prediction - observation|^2 of one measurement at the pose T_c_w, and the
/// depth z of p_w in that camera (when depth_m is non-null).
double reprojection_chi2(const CameraIntrinsics& camera, const SE3& T_c_w, const Vec3d& p_w,
                         const Measurement& measurement, double* depth_m = nullptr);

}  // namespace ddl::optimization
