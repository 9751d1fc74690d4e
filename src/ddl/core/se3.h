#pragma once
// Rigid-body transforms (no Sophus in Debian): SO(3)/SE(3) exponential and logarithm maps and a
// small SE3 value type. Naming rule (ARCHITECTURE.md section 5): T_a_b maps coordinates expressed
// in frame b into frame a, so T_w_c * p_c = p_w and T_a_b * T_b_c = T_a_c.
// Tangent vectors are ordered [rho (translation part); phi (rotation part)].

#include "ddl/core/types.h"

namespace ddl {

/// Skew-symmetric matrix with hat(a) * b == a.cross(b).
Mat3d hat(const Vec3d& v);

/// Rotation matrix of the rotation vector phi (Rodrigues), exact near zero.
Mat3d so3_exp(const Vec3d& phi);
/// Rotation vector (axis * angle, angle in [0, pi]) of a rotation matrix; robust near 0 and pi.
Vec3d so3_log(const Mat3d& R);
/// Left Jacobian of SO(3) and its inverse.
Mat3d so3_left_jacobian(const Vec3d& phi);
Mat3d so3_left_jacobian_inverse(const Vec3d& phi);

class SE3 {
 public:
  SE3() : q_(Quatd::Identity()), t_(Vec3d::Zero()) {}
  SE3(const Quatd& q, const Vec3d& t) : q_(q.normalized()), t_(t) {}
  SE3(const Mat3d& R, const Vec3d& t) : q_(Quatd(R).normalized()), t_(t) {}
  /// From a homogeneous 4x4 matrix; the rotation block is re-orthonormalised.
  explicit SE3(const Mat4d& T);

  static SE3 identity() { return SE3(); }
  /// exp of the twist xi = [rho; phi].
  static SE3 exp(const Vec6d& xi);
  /// Twist xi = [rho; phi] with exp(xi) == *this.
  Vec6d log() const;

  const Quatd& quaternion() const { return q_; }
  Mat3d rotation() const { return q_.toRotationMatrix(); }
  const Vec3d& translation() const { return t_; }
  Vec3d& translation() { return t_; }
  Mat4d matrix() const;
  /// Rotation as rotation vector (axis * angle).
  Vec3d rotation_vector() const { return so3_log(rotation()); }

  SE3 inverse() const;
  SE3 operator*(const SE3& other) const { return SE3(q_ * other.q_, q_ * other.t_ + t_); }
  Vec3d operator*(const Vec3d& p) const { return q_ * p + t_; }

  /// 6x6 adjoint: Ad(T) * xi == log(T * exp(xi) * T^-1).
  Mat6d adjoint() const;

  /// Angle of the rotation part in radians, in [0, pi].
  double rotation_angle() const;

 private:
  Quatd q_;
  Vec3d t_;
};

/// Linear interpolation of translation and slerp of rotation, s in [0, 1].
SE3 interpolate(const SE3& a, const SE3& b, double s);

}  // namespace ddl
