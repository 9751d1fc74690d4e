#include "ddl/eval/alignment.h"

#include <gtest/gtest.h>

#include <random>

#include "ddl/core/error.h"
#include "ddl/core/se3.h"

namespace ddl::eval {
namespace {

Eigen::Matrix3Xd random_points(int n, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u(-2.0, 2.0);
  Eigen::Matrix3Xd p(3, n);
  for (int i = 0; i < n; ++i) p.col(i) = Vec3d(u(rng), u(rng), 0.5 * u(rng));
  return p;
}

TEST(AlignmentTest, HornRecoversKnownRigidTransform) {
  const Eigen::Matrix3Xd model = random_points(50, 1);
  const Mat3d R = so3_exp(Vec3d(0.3, -1.1, 2.0));
  const Vec3d t(1.5, -0.25, 3.0);
  const Eigen::Matrix3Xd data = (R * model).colwise() + t;

  const Alignment a = align_horn(model, data);
  EXPECT_LT((a.R_gt_est - R).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((a.t_gt_est - t).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(a.scale, 1.0);
  EXPECT_LT((a.apply(model) - data).cwiseAbs().maxCoeff(), 1e-9);
}

TEST(AlignmentTest, HornIgnoresScaleButUmeyamaRecoversIt) {
  const Eigen::Matrix3Xd model = random_points(40, 2);
  const Mat3d R = so3_exp(Vec3d(-0.7, 0.2, 0.9));
  const Vec3d t(-2.0, 0.5, 0.75);
  const double s = 2.5;
  const Eigen::Matrix3Xd data = ((s * R) * model).colwise() + t;

  const Alignment u = align_umeyama(model, data, /*with_scale=*/true);
  EXPECT_NEAR(u.scale, s, 1e-9);
  EXPECT_LT((u.R_gt_est - R).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((u.t_gt_est - t).cwiseAbs().maxCoeff(), 1e-9);

  // Rigid alignment still finds the rotation (it does not depend on scale) but leaves residuals.
  const Alignment h = align_horn(model, data);
  EXPECT_EQ(h.scale, 1.0);
  EXPECT_LT((h.R_gt_est - R).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_GT((h.apply(model) - data).colwise().norm().maxCoeff(), 0.1);
}

TEST(AlignmentTest, ReflectedDataStillGivesAProperRotation) {
  const Eigen::Matrix3Xd model = random_points(30, 3);
  Eigen::Matrix3Xd data = model;
  data.row(2) *= -1.0;  // a mirror image: the best orthogonal map would be a reflection
  const Alignment a = align_horn(model, data);
  EXPECT_NEAR(a.R_gt_est.determinant(), 1.0, 1e-12);
  EXPECT_LT((a.R_gt_est.transpose() * a.R_gt_est - Mat3d::Identity()).cwiseAbs().maxCoeff(), 1e-12);
}

TEST(AlignmentTest, RejectsMismatchedOrEmptyInput) {
  EXPECT_THROW(align_horn(random_points(5, 4), random_points(6, 4)), Error);
  EXPECT_THROW(align_horn(Eigen::Matrix3Xd(3, 0), Eigen::Matrix3Xd(3, 0)), Error);
  const Eigen::Matrix3Xd same = Vec3d(1, 2, 3).replicate(1, 4);
  EXPECT_THROW(align_umeyama(same, same, true), Error);
}

}  // namespace
}  // namespace ddl::eval
