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

// A camera on a tripod: positions within +-1 mm, orientations within a few degrees, with 1 mm /
// 0.1 degree estimation noise. The position-only fit cannot determine the rotation; the pose
// fit recovers it to well below a degree.
TEST(AlignmentTest, PoseAlignmentStaysDeterminedForACameraThatHardlyMoves) {
  std::mt19937 rng(7);
  std::normal_distribution<double> noise(0.0, 1.0);
  const SE3 T_gt_est(so3_exp(Vec3d(0.4, -0.9, 1.7)), Vec3d(2.0, 1.0, 1.4));
  std::vector<SE3> gt;
  std::vector<SE3> est;
  Eigen::Matrix3Xd gt_xyz(3, 100);
  Eigen::Matrix3Xd est_xyz(3, 100);
  for (int i = 0; i < 100; ++i) {
    const SE3 T_est_w_c(so3_exp(0.05 * Vec3d(noise(rng), noise(rng), noise(rng))),
                        0.001 * Vec3d(noise(rng), noise(rng), noise(rng)));
    const SE3 error(so3_exp(0.0017 * Vec3d(noise(rng), noise(rng), noise(rng))),
                    0.001 * Vec3d(noise(rng), noise(rng), noise(rng)));
    est.push_back(T_est_w_c);
    gt.push_back(T_gt_est * T_est_w_c * error);
    est_xyz.col(i) = est.back().translation();
    gt_xyz.col(i) = gt.back().translation();
  }
  auto angle_deg = [](const Mat3d& a, const Mat3d& b) {
    return so3_log(a * b.transpose()).norm() * 180.0 / M_PI;
  };
  const Alignment poses = align_poses(gt, est);
  EXPECT_LT(angle_deg(poses.R_gt_est, T_gt_est.rotation()), 0.1);
  EXPECT_LT((poses.t_gt_est - T_gt_est.translation()).norm(), 0.002);
  const Alignment positions = align_horn(est_xyz, gt_xyz);
  EXPECT_GT(angle_deg(positions.R_gt_est, T_gt_est.rotation()), 5.0);
  EXPECT_THROW(align_poses(gt, {}), Error);
}

}  // namespace
}  // namespace ddl::eval
