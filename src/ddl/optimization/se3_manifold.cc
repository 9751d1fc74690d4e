#include "ddl/optimization/se3_manifold.h"

#include <cmath>

namespace ddl::optimization {
namespace {

/// Below this rotation angle the coefficients of Q use their Taylor series: the closed forms
/// cancel catastrophically (c3's numerator is ~theta^5 / 60).
constexpr double kSeriesAngle = 0.1;

/// Unit quaternion of the rotation vector phi with w = cos(|phi| / 2) >= 0.
Quatd quaternion_exp(const Vec3d& phi) {
  const double theta = phi.norm();
  if (theta < 1e-8) return Quatd(1.0, 0.5 * phi.x(), 0.5 * phi.y(), 0.5 * phi.z()).normalized();
  const double half = 0.5 * theta;
  const Vec3d v = phi * (std::sin(half) / theta);
  return Quatd(std::cos(half), v.x(), v.y(), v.z());
}

Mat3d se3_q_matrix(const Vec3d& rho, const Vec3d& phi) {
  const double theta = phi.norm();
  const double t2 = theta * theta;
  double c1 = 0.0;
  double c2 = 0.0;
  double c3 = 0.0;
  if (theta < kSeriesAngle) {
    const double t4 = t2 * t2;
    c1 = 1.0 / 6.0 - t2 / 120.0 + t4 / 5040.0;
    c2 = 1.0 / 24.0 - t2 / 720.0 + t4 / 40320.0;
    c3 = 1.0 / 120.0 - t2 / 2520.0 + t4 / 120960.0;
  } else {
    const double s = std::sin(theta);
    const double c = std::cos(theta);
    c1 = (theta - s) / (t2 * theta);
    c2 = (t2 + 2.0 * c - 2.0) / (2.0 * t2 * t2);
    c3 = (2.0 * theta - 3.0 * s + theta * c) / (2.0 * t2 * t2 * theta);
  }
  const Mat3d P = hat(phi);
  const Mat3d R = hat(rho);
  const Mat3d PR = P * R;
  const Mat3d RP = R * P;
  const Mat3d PRP = PR * P;
  const Mat3d PP = P * P;
  return 0.5 * R + c1 * (PR + RP + PRP) + c2 * (PP * R + RP * P - 3.0 * PRP) +
         c3 * (PRP * P + PP * RP);
}

}  // namespace

PoseParameters to_parameters(const SE3& T) {
  const Quatd& q = T.quaternion();
  const Vec3d& t = T.translation();
  return {q.x(), q.y(), q.z(), q.w(), t.x(), t.y(), t.z()};
}

SE3 from_parameters(const double* x) {
  return SE3(Quatd(x[3], x[0], x[1], x[2]), Vec3d(x[4], x[5], x[6]));
}

MinusJacobianMatrix pose_minus_jacobian(const double* x) {
  MinusJacobianMatrix J;
  tangent_to_ambient<6>(Mat6d::Identity(), x, J.data());
  return J;
}

bool SE3Manifold::Plus(const double* x, const double* delta, double* x_plus_delta) const {
  const Eigen::Map<const Quatd> q(x);
  const Eigen::Map<const Vec3d> t(x + 4);
  const Eigen::Map<const Vec3d> rho(delta);
  const Eigen::Map<const Vec3d> phi(delta + 3);
  // exp(delta) = (R(phi), J_l(phi) rho); exp(delta) * T = (R(phi) R, R(phi) t + J_l(phi) rho).
  const Quatd dq = quaternion_exp(phi);
  Eigen::Map<Quatd> q_out(x_plus_delta);
  Eigen::Map<Vec3d> t_out(x_plus_delta + 4);
  q_out = (dq * q).normalized();
  t_out = dq * t + so3_left_jacobian(phi) * rho;
  return true;
}

bool SE3Manifold::PlusJacobian(const double* x, double* jacobian) const {
  // d Plus(x, delta) / d delta at delta = 0. Quaternion rows: (0, phi / 2) (x) q, i.e.
  // 0.5 [w I - hat(v); -v^T] phi; translation rows: rho - hat(t) phi.
  const Eigen::Map<const Vec3d> v(x);
  const double w = x[3];
  const Eigen::Map<const Vec3d> t(x + 4);
  Eigen::Map<Eigen::Matrix<double, kPoseAmbientSize, kPoseTangentSize, Eigen::RowMajor>> J(
      jacobian);
  J.setZero();
  J.block<3, 3>(0, 3) = 0.5 * (w * Mat3d::Identity() - hat(v));
  J.block<1, 3>(3, 3) = -0.5 * v.transpose();
  J.block<3, 3>(4, 0) = Mat3d::Identity();
  J.block<3, 3>(4, 3) = -hat(t);
  return true;
}

bool SE3Manifold::Minus(const double* y, const double* x, double* y_minus_x) const {
  const SE3 Y = from_parameters(y);
  const SE3 X = from_parameters(x);
  Eigen::Map<Vec6d> out(y_minus_x);
  out = (Y * X.inverse()).log();
  return true;
}

bool SE3Manifold::MinusJacobian(const double* x, double* jacobian) const {
  Eigen::Map<MinusJacobianMatrix> out(jacobian);
  out = pose_minus_jacobian(x);
  return true;
}

Mat6d se3_left_jacobian(const Vec6d& xi) {
  const Vec3d rho = xi.head<3>();
  const Vec3d phi = xi.tail<3>();
  const Mat3d J = so3_left_jacobian(phi);
  Mat6d out = Mat6d::Zero();
  out.block<3, 3>(0, 0) = J;
  out.block<3, 3>(0, 3) = se3_q_matrix(rho, phi);
  out.block<3, 3>(3, 3) = J;
  return out;
}

Mat6d se3_left_jacobian_inverse(const Vec6d& xi) {
  const Vec3d rho = xi.head<3>();
  const Vec3d phi = xi.tail<3>();
  const Mat3d J_inv = so3_left_jacobian_inverse(phi);
  Mat6d out = Mat6d::Zero();
  out.block<3, 3>(0, 0) = J_inv;
  out.block<3, 3>(0, 3) = -J_inv * se3_q_matrix(rho, phi) * J_inv;
  out.block<3, 3>(3, 3) = J_inv;
  return out;
}

}  // namespace ddl::optimization
