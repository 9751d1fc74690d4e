#pragma once
// SE(3) as a Ceres manifold (Ceres 2.1 Manifold API) and the Jacobian helpers that let the
// analytic cost functions of this module hand Ceres ambient-space Jacobians.
//
// Ambient parameters (7): [qx, qy, qz, qw, tx, ty, tz] -- the unit quaternion in Eigen's
// coefficient order (x, y, z, w), then the translation. The pair represents T = (R(q), t); q and -q
// are the same pose (Plus keeps the sign it is given, Minus ignores it).
//
// Tangent (6): delta = [rho; phi] (translation part first, as ddl::SE3::exp), applied as a LEFT
// perturbation:  Plus(T, delta) = SE3::exp(delta) * T,  Minus(Y, X) = log(Y * X^-1).
// For a world-to-camera pose T_c_w the perturbation therefore acts in the camera frame, and a
// camera point p_c = T_c_w * p_w moves by d p_c / d delta = [I, -hat(p_c)] (the g2o
// VertexSE3Expmap convention with the two halves of the tangent swapped).

#include <ceres/manifold.h>

#include <array>

#include "ddl/core/se3.h"

namespace ddl::optimization {

inline constexpr int kPoseAmbientSize = 7;
inline constexpr int kPoseTangentSize = 6;
using PoseParameters = std::array<double, kPoseAmbientSize>;

/// [qx, qy, qz, qw, tx, ty, tz] of T.
PoseParameters to_parameters(const SE3& T);
/// Pose of 7 ambient parameters (the quaternion is normalised).
SE3 from_parameters(const double* x);

/// Row-major 6x7 derivative of Minus(y, x) with respect to y at y = x. Ceres only ever uses an
/// ambient Jacobian J_amb through J_amb * PlusJacobian(x), and MinusJacobian(x) * PlusJacobian(x)
/// = I, so a cost function with a tangent Jacobian J_tan may report J_amb = J_tan * MinusJacobian.
using MinusJacobianMatrix =
    Eigen::Matrix<double, kPoseTangentSize, kPoseAmbientSize, Eigen::RowMajor>;
MinusJacobianMatrix pose_minus_jacobian(const double* x);

/// Writes J_amb = J_tan * MinusJacobian(x) (Rows x 7, row-major) for a tangent Jacobian
/// (Rows x 6) at the pose x, without forming the 6x7 matrix. Inline: called per residual.
template <int Rows>
inline void tangent_to_ambient(const Eigen::Matrix<double, Rows, 6>& J_tan, const double* x,
                               double* J_amb) {
  // MinusJacobian = [[hat(t) D, I], [D, 0]] with D = 2 [w I + hat(v) | -v] (3x4, quaternion
  // columns x, y, z, w), so J_amb = [(J_rho hat(t) + J_phi) D | J_rho].
  const Eigen::Map<const Vec3d> v(x);
  const double w = x[3];
  const Eigen::Map<const Vec3d> t(x + 4);
  const Eigen::Matrix<double, Rows, 3> J_rho = J_tan.template leftCols<3>();
  const Eigen::Matrix<double, Rows, 3> G = J_rho * hat(t) + J_tan.template rightCols<3>();
  Eigen::Matrix<double, 3, 4> D;
  D.leftCols<3>() = 2.0 * (w * Mat3d::Identity() + hat(v));
  D.col(3) = -2.0 * v;
  Eigen::Map<Eigen::Matrix<double, Rows, kPoseAmbientSize, Eigen::RowMajor>> out(J_amb);
  out.template leftCols<4>() = G * D;
  out.template rightCols<3>() = J_rho;
}

class SE3Manifold final : public ceres::Manifold {
 public:
  int AmbientSize() const override { return kPoseAmbientSize; }
  int TangentSize() const override { return kPoseTangentSize; }
  bool Plus(const double* x, const double* delta, double* x_plus_delta) const override;
  bool PlusJacobian(const double* x, double* jacobian) const override;
  bool Minus(const double* y, const double* x, double* y_minus_x) const override;
  bool MinusJacobian(const double* x, double* jacobian) const override;
};

/// SE(3) left Jacobian for xi = [rho; phi]: log(exp(a) * exp(xi)) ~= xi + J_l(xi)^-1 * a.
/// Block form [[J, Q], [0, J]] with J the SO(3) left Jacobian and Q Barfoot's coupling term.
Mat6d se3_left_jacobian(const Vec6d& xi);
Mat6d se3_left_jacobian_inverse(const Vec6d& xi);

}  // namespace ddl::optimization
