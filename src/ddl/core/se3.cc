#include "ddl/core/se3.h"

#include <Eigen/SVD>
#include <cmath>

namespace ddl {
namespace {
constexpr double kSmallAngle = 1e-8;
}  // namespace

Mat3d hat(const Vec3d& v) {
  Mat3d m;
  m << 0.0, -v.z(), v.y(), v.z(), 0.0, -v.x(), -v.y(), v.x(), 0.0;
  return m;
}

Mat3d so3_exp(const Vec3d& phi) {
  const double theta = phi.norm();
  if (theta < kSmallAngle) return Mat3d::Identity() + hat(phi);
  return Eigen::AngleAxisd(theta, phi / theta).toRotationMatrix();
}

Vec3d so3_log(const Mat3d& R) {
  // Through the quaternion: numerically stable at both ends of [0, pi].
  Quatd q(R);
  q.normalize();
  if (q.w() < 0.0) q.coeffs() = -q.coeffs();
  const double sin_half = q.vec().norm();
  if (sin_half < kSmallAngle) return 2.0 * q.vec() / q.w();
  const double theta = 2.0 * std::atan2(sin_half, q.w());
  return q.vec() * (theta / sin_half);
}

Mat3d so3_left_jacobian(const Vec3d& phi) {
  const double theta = phi.norm();
  const Mat3d K = hat(phi);
  if (theta < 1e-5) return Mat3d::Identity() + 0.5 * K + K * K / 6.0;
  const double t2 = theta * theta;
  return Mat3d::Identity() + (1.0 - std::cos(theta)) / t2 * K +
         (theta - std::sin(theta)) / (t2 * theta) * K * K;
}

Mat3d so3_left_jacobian_inverse(const Vec3d& phi) {
  const double theta = phi.norm();
  const Mat3d K = hat(phi);
  if (theta < 1e-5) return Mat3d::Identity() - 0.5 * K + K * K / 12.0;
  const double half = 0.5 * theta;
  const double cot_term = (1.0 - half * std::cos(half) / std::sin(half)) / (theta * theta);
  return Mat3d::Identity() - 0.5 * K + cot_term * K * K;
}

SE3::SE3(const Mat4d& T) : t_(T.block<3, 1>(0, 3)) {
  Eigen::JacobiSVD<Mat3d> svd(T.block<3, 3>(0, 0), Eigen::ComputeFullU | Eigen::ComputeFullV);
  Mat3d R = svd.matrixU() * svd.matrixV().transpose();
  if (R.determinant() < 0.0) {
    Mat3d U = svd.matrixU();
    U.col(2) *= -1.0;
    R = U * svd.matrixV().transpose();
  }
  q_ = Quatd(R).normalized();
}

SE3 SE3::exp(const Vec6d& xi) {
  const Vec3d rho = xi.head<3>();
  const Vec3d phi = xi.tail<3>();
  return SE3(so3_exp(phi), so3_left_jacobian(phi) * rho);
}

Vec6d SE3::log() const {
  const Vec3d phi = so3_log(rotation());
  Vec6d xi;
  xi.head<3>() = so3_left_jacobian_inverse(phi) * t_;
  xi.tail<3>() = phi;
  return xi;
}

Mat4d SE3::matrix() const {
  Mat4d T = Mat4d::Identity();
  T.block<3, 3>(0, 0) = rotation();
  T.block<3, 1>(0, 3) = t_;
  return T;
}

SE3 SE3::inverse() const {
  const Quatd q_inv = q_.conjugate();
  return SE3(q_inv, -(q_inv * t_));
}

Mat6d SE3::adjoint() const {
  const Mat3d R = rotation();
  Mat6d ad = Mat6d::Zero();
  ad.block<3, 3>(0, 0) = R;
  ad.block<3, 3>(0, 3) = hat(t_) * R;
  ad.block<3, 3>(3, 3) = R;
  return ad;
}

double SE3::rotation_angle() const { return so3_log(rotation()).norm(); }

SE3 interpolate(const SE3& a, const SE3& b, double s) {
  return SE3(a.quaternion().slerp(s, b.quaternion()),
             (1.0 - s) * a.translation() + s * b.translation());
}

}  // namespace ddl
