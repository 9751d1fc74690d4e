#include "ddl/core/se3.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>

namespace ddl {
namespace {

SE3 random_pose(std::mt19937& rng, double max_angle) {
  std::uniform_real_distribution<double> u(-1.0, 1.0);
  Vec3d axis(u(rng), u(rng), u(rng));
  axis.normalize();
  const double angle = std::abs(u(rng)) * max_angle;
  return SE3(Mat3d(Eigen::AngleAxisd(angle, axis)), Vec3d(u(rng), u(rng), u(rng)));
}

TEST(SE3, ExpLogRoundTrip) {
  std::mt19937 rng(1);
  for (int i = 0; i < 200; ++i) {
    const SE3 T = random_pose(rng, 3.1);
    const SE3 back = SE3::exp(T.log());
    EXPECT_LT((back.matrix() - T.matrix()).norm(), 1e-10) << "sample " << i;
  }
}

TEST(SE3, LogExpRoundTripNearIdentityAndPi) {
  for (double angle : {0.0, 1e-12, 1e-6, 1e-3, 1.0, M_PI - 1e-6}) {
    Vec6d xi;
    xi << 0.3, -0.2, 0.1, Vec3d(1, 2, 3).normalized() * angle;
    const Vec6d back = SE3::exp(xi).log();
    EXPECT_LT((back - xi).norm(), 1e-8) << "angle " << angle;
  }
}

TEST(SE3, QuaternionMatrixRoundTrip) {
  std::mt19937 rng(2);
  for (int i = 0; i < 100; ++i) {
    const SE3 T = random_pose(rng, M_PI);
    const SE3 from_matrix(T.matrix());
    EXPECT_LT((from_matrix.matrix() - T.matrix()).norm(), 1e-12);
    // q and -q are the same rotation.
    EXPECT_NEAR(std::abs(from_matrix.quaternion().dot(T.quaternion())), 1.0, 1e-12);
  }
}

TEST(SE3, CompositionInverseAndPoints) {
  std::mt19937 rng(3);
  const SE3 T_a_b = random_pose(rng, 2.0);
  const SE3 T_b_c = random_pose(rng, 2.0);
  const Vec3d p_c(0.5, -1.0, 2.0);
  EXPECT_LT(((T_a_b * T_b_c) * p_c - T_a_b * (T_b_c * p_c)).norm(), 1e-12);
  EXPECT_LT(((T_a_b * T_a_b.inverse()).matrix() - Mat4d::Identity()).norm(), 1e-12);
  EXPECT_LT(((T_a_b * T_b_c).matrix() - T_a_b.matrix() * T_b_c.matrix()).norm(), 1e-12);
}

TEST(SE3, AdjointMapsTwists) {
  std::mt19937 rng(4);
  const SE3 T = random_pose(rng, 2.0);
  Vec6d xi;
  xi << 0.01, -0.02, 0.03, 0.02, 0.01, -0.015;
  const SE3 lhs = T * SE3::exp(xi) * T.inverse();
  const SE3 rhs = SE3::exp(T.adjoint() * xi);
  EXPECT_LT((lhs.matrix() - rhs.matrix()).norm(), 1e-10);
}

TEST(SO3, LeftJacobianInverse) {
  for (double angle : {1e-7, 0.1, 1.5, 3.0}) {
    const Vec3d phi = Vec3d(0.2, -0.5, 0.8).normalized() * angle;
    const Mat3d prod = so3_left_jacobian(phi) * so3_left_jacobian_inverse(phi);
    EXPECT_LT((prod - Mat3d::Identity()).norm(), 1e-9) << angle;
  }
}

TEST(SE3, RotationAngle) {
  const SE3 T(Mat3d(Eigen::AngleAxisd(0.7, Vec3d::UnitZ())), Vec3d(1, 2, 3));
  EXPECT_NEAR(T.rotation_angle(), 0.7, 1e-12);
}

}  // namespace
}  // namespace ddl
