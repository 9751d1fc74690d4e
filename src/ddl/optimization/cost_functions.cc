#include "ddl/optimization/cost_functions.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ddl::optimization {
namespace {

constexpr double kMinAbsDepth = 1e-12;

}  // namespace

template <int N>
ReprojectionModel<N>::ReprojectionModel(const CameraIntrinsics& camera,
                                        const Measurement& measurement)
    : fx_(camera.fx),
      fy_(camera.fy),
      cx_(camera.cx),
      cy_(camera.cy),
      bf_(camera.bf),
      sqrt_info_(std::sqrt(measurement.inv_sigma2)) {
  observed_[0] = measurement.uv_px.x();
  observed_[1] = measurement.uv_px.y();
  if constexpr (N == 3) observed_[2] = measurement.u_right_px;
}

template <int N>
void ReprojectionModel<N>::evaluate(const Vec3d& p_c, Residual* r, PointJacobian* J) const {
  const double z = p_c.z();
  if (std::abs(z) < kMinAbsDepth) {
    r->setZero();
    if (J != nullptr) J->setZero();
    return;
  }
  const double inv_z = 1.0 / z;
  const double x_n = p_c.x() * inv_z;
  const double y_n = p_c.y() * inv_z;
  const double u = fx_ * x_n + cx_;
  (*r)[0] = sqrt_info_ * (u - observed_[0]);
  (*r)[1] = sqrt_info_ * (fy_ * y_n + cy_ - observed_[1]);
  if constexpr (N == 3) (*r)[2] = sqrt_info_ * (u - bf_ * inv_z - observed_[2]);
  if (J == nullptr) return;
  const double s = sqrt_info_ * inv_z;
  (*J)(0, 0) = s * fx_;
  (*J)(0, 1) = 0.0;
  (*J)(0, 2) = -s * fx_ * x_n;
  (*J)(1, 0) = 0.0;
  (*J)(1, 1) = s * fy_;
  (*J)(1, 2) = -s * fy_ * y_n;
  if constexpr (N == 3) {
    (*J)(2, 0) = (*J)(0, 0);
    (*J)(2, 1) = 0.0;
    (*J)(2, 2) = (*J)(0, 2) + s * bf_ * inv_z;
  }
}

template <int N>
bool PoseReprojectionCost<N>::Evaluate(double const* const* parameters, double* residuals,
                                       double** jacobians) const {
  Eigen::Map<Eigen::Matrix<double, N, 1>> r(residuals);
  const bool want_jacobian = jacobians != nullptr && jacobians[0] != nullptr;
  if (active_ != nullptr && *active_ == 0) {
    r.setZero();
    if (want_jacobian) std::fill_n(jacobians[0], N * kPoseAmbientSize, 0.0);
    return true;
  }
  const double* x = parameters[0];
  const Eigen::Map<const Quatd> q(x);
  const Eigen::Map<const Vec3d> t(x + 4);
  const Vec3d p_c = q * p_w_ + t;
  typename ReprojectionModel<N>::Residual res;
  if (!want_jacobian) {
    model_.evaluate(p_c, &res, nullptr);
    r = res;
    return true;
  }
  typename ReprojectionModel<N>::PointJacobian J_p;
  model_.evaluate(p_c, &res, &J_p);
  r = res;
  // Left perturbation: d p_c / d [rho; phi] = [I, -hat(p_c)].
  Eigen::Matrix<double, N, 6> J_tan;
  J_tan.template leftCols<3>() = J_p;
  J_tan.template rightCols<3>() = -J_p * hat(p_c);
  tangent_to_ambient<N>(J_tan, x, jacobians[0]);
  return true;
}

template <int N>
bool BaReprojectionCost<N>::Evaluate(double const* const* parameters, double* residuals,
                                     double** jacobians) const {
  Eigen::Map<Eigen::Matrix<double, N, 1>> r(residuals);
  double* J_pose_out = jacobians != nullptr ? jacobians[0] : nullptr;
  double* J_point_out = jacobians != nullptr ? jacobians[1] : nullptr;
  if (active_ != nullptr && *active_ == 0) {
    r.setZero();
    if (J_pose_out != nullptr) std::fill_n(J_pose_out, N * kPoseAmbientSize, 0.0);
    if (J_point_out != nullptr) std::fill_n(J_point_out, N * 3, 0.0);
    return true;
  }
  const double* x = parameters[0];
  const Eigen::Map<const Quatd> q(x);
  const Eigen::Map<const Vec3d> t(x + 4);
  const Eigen::Map<const Vec3d> p_w(parameters[1]);
  const Vec3d p_c = q * p_w + t;
  typename ReprojectionModel<N>::Residual res;
  if (J_pose_out == nullptr && J_point_out == nullptr) {
    model_.evaluate(p_c, &res, nullptr);
    r = res;
    return true;
  }
  typename ReprojectionModel<N>::PointJacobian J_p;
  model_.evaluate(p_c, &res, &J_p);
  r = res;
  if (J_pose_out != nullptr) {
    Eigen::Matrix<double, N, 6> J_tan;
    J_tan.template leftCols<3>() = J_p;
    J_tan.template rightCols<3>() = -J_p * hat(p_c);
    tangent_to_ambient<N>(J_tan, x, J_pose_out);
  }
  if (J_point_out != nullptr) {
    Eigen::Map<Eigen::Matrix<double, N, 3, Eigen::RowMajor>> J_point(J_point_out);
    J_point = J_p * q.toRotationMatrix();
  }
  return true;
}

PoseGraphEdgeCost::PoseGraphEdgeCost(const SE3& T_i_j, const Mat6d& sqrt_information)
    : T_j_i_measured_(T_i_j.inverse()),
      adjoint_T_j_i_(T_j_i_measured_.adjoint()),
      sqrt_information_(sqrt_information) {}

bool PoseGraphEdgeCost::Evaluate(double const* const* parameters, double* residuals,
                                 double** jacobians) const {
  const SE3 T_i_w = from_parameters(parameters[0]);
  const SE3 T_j_w = from_parameters(parameters[1]);
  const SE3 E = T_j_i_measured_ * T_i_w * T_j_w.inverse();
  const Vec6d e = E.log();
  Eigen::Map<Vec6d> r(residuals);
  r = sqrt_information_ * e;
  if (jacobians == nullptr) return true;
  const Mat6d S_Jinv = sqrt_information_ * se3_left_jacobian_inverse(e);
  // T_i <- exp(d) T_i:  E <- M^-1 exp(d) M E = exp(Ad(M^-1) d) E.
  // T_j <- exp(d) T_j:  E <- E exp(-d) = exp(-Ad(E) d) E.
  if (jacobians[0] != nullptr) {
    const Eigen::Matrix<double, 6, 6> J_i = S_Jinv * adjoint_T_j_i_;
    tangent_to_ambient<6>(J_i, parameters[0], jacobians[0]);
  }
  if (jacobians[1] != nullptr) {
    const Eigen::Matrix<double, 6, 6> J_j = -S_Jinv * E.adjoint();
    tangent_to_ambient<6>(J_j, parameters[1], jacobians[1]);
  }
  return true;
}

PosePriorCost::PosePriorCost(const SE3& T_c_w_prior, const Mat6d& sqrt_information)
    : T_w_c_prior_(T_c_w_prior.inverse()), sqrt_information_(sqrt_information) {}

bool PosePriorCost::Evaluate(double const* const* parameters, double* residuals,
                             double** jacobians) const {
  const SE3 E = from_parameters(parameters[0]) * T_w_c_prior_;
  const Vec6d e = E.log();
  Eigen::Map<Vec6d> r(residuals);
  r = sqrt_information_ * e;
  if (jacobians == nullptr || jacobians[0] == nullptr) return true;
  // T <- exp(d) T:  E <- exp(d) E, log(exp(d) E) ~= e + J_l(e)^-1 d.
  const Eigen::Matrix<double, 6, 6> J = sqrt_information_ * se3_left_jacobian_inverse(e);
  tangent_to_ambient<6>(J, parameters[0], jacobians[0]);
  return true;
}

double reprojection_chi2(const CameraIntrinsics& camera, const SE3& T_c_w, const Vec3d& p_w,
                         const Measurement& measurement, double* depth_m) {
  const Vec3d p_c = T_c_w * p_w;
  if (depth_m != nullptr) *depth_m = p_c.z();
  // On the camera plane the residual is not defined (the cost functions return zero there).
  if (std::abs(p_c.z()) < kMinAbsDepth) return std::numeric_limits<double>::infinity();
  if (measurement.stereo) {
    Eigen::Matrix<double, 3, 1> r;
    ReprojectionModel<3>(camera, measurement).evaluate(p_c, &r, nullptr);
    return r.squaredNorm();
  }
  Eigen::Matrix<double, 2, 1> r;
  ReprojectionModel<2>(camera, measurement).evaluate(p_c, &r, nullptr);
  return r.squaredNorm();
}

template class ReprojectionModel<2>;
template class ReprojectionModel<3>;
template class PoseReprojectionCost<2>;
template class PoseReprojectionCost<3>;
template class BaReprojectionCost<2>;
template class BaReprojectionCost<3>;

}  // namespace ddl::optimization
