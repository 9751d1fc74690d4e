// 3D-3D relative pose: closed form and RANSAC with outliers, deterministic for a seed.

#include "ddl/loop/relative_pose.h"

#include <gtest/gtest.h>

#include "synthetic_world.h"

namespace ddl::loop {
namespace {

optimization::CameraIntrinsics camera() { return {525.0, 525.0, 319.5, 239.5, test::kBf}; }

TEST(FitRigidTransform, RecoversExactTransform) {
  std::mt19937_64 rng(3);
  const SE3 T = SE3::exp((Vec6d() << 0.3, -0.2, 0.5, 0.1, -0.4, 0.25).finished());
  std::vector<Vec3d> src, dst;
  for (int i = 0; i < 10; ++i) {
    src.emplace_back(test::uniform(rng, -1, 1), test::uniform(rng, -1, 1),
                     test::uniform(rng, 1, 4));
    dst.push_back(T * src.back());
  }
  const auto fit = fit_rigid_transform(src, dst);
  ASSERT_TRUE(fit);
  EXPECT_LT((fit->matrix() - T.matrix()).norm(), 1e-9);
}

TEST(FitRigidTransform, DegenerateInputGivesNothing) {
  const std::vector<Vec3d> line = {Vec3d(0, 0, 1), Vec3d(0, 0, 2), Vec3d(0, 0, 3)};
  EXPECT_FALSE(fit_rigid_transform(line, line));
  const std::vector<Vec3d> two = {Vec3d(0, 0, 1), Vec3d(1, 0, 2)};
  EXPECT_FALSE(fit_rigid_transform(two, two));
}

/// Correspondences of `n` points seen by two cameras with T_1_2, a fraction of them outliers.
std::vector<PointCorrespondence> make_correspondences(const SE3& T_1_2, int n,
                                                      double outlier_fraction,
                                                      std::mt19937_64& rng) {
  const auto cam = camera();
  std::vector<PointCorrespondence> out;
  while (static_cast<int>(out.size()) < n) {
    const Vec3d p2(test::uniform(rng, -1.5, 1.5), test::uniform(rng, -1, 1),
                   test::uniform(rng, 1.5, 4));
    const Vec3d p1 = T_1_2 * p2;
    if (p1.z() < 0.5) continue;
    PointCorrespondence c;
    c.p1_c = p1 + 0.003 * Vec3d(test::gaussian(rng), test::gaussian(rng), test::gaussian(rng));
    c.p2_c = p2 + 0.003 * Vec3d(test::gaussian(rng), test::gaussian(rng), test::gaussian(rng));
    c.uv1 = Vec2d(cam.fx * p1.x() / p1.z() + cam.cx, cam.fy * p1.y() / p1.z() + cam.cy) +
            0.3 * Vec2d(test::gaussian(rng), test::gaussian(rng));
    c.uv2 = Vec2d(cam.fx * p2.x() / p2.z() + cam.cx, cam.fy * p2.y() / p2.z() + cam.cy) +
            0.3 * Vec2d(test::gaussian(rng), test::gaussian(rng));
    if (test::uniform(rng, 0, 1) < outlier_fraction) {
      // A wrong match: some other point of the scene.
      c.p1_c = Vec3d(test::uniform(rng, -1.5, 1.5), test::uniform(rng, -1, 1),
                     test::uniform(rng, 1.5, 4));
      c.uv1 = Vec2d(cam.fx * c.p1_c.x() / c.p1_c.z() + cam.cx,
                    cam.fy * c.p1_c.y() / c.p1_c.z() + cam.cy);
    }
    out.push_back(c);
  }
  return out;
}

TEST(EstimateRelativePose, FindsPoseDespiteFortyPercentOutliers) {
  std::mt19937_64 rng(5);
  const SE3 T_1_2 = SE3::exp((Vec6d() << 0.2, 0.05, -0.1, 0.02, 0.15, -0.03).finished());
  const auto correspondences = make_correspondences(T_1_2, 100, 0.4, rng);
  const auto estimate = estimate_relative_pose(correspondences, camera(), {});
  ASSERT_TRUE(estimate);
  EXPECT_LT((estimate->T_1_2.translation() - T_1_2.translation()).norm(), 0.005);
  EXPECT_LT(test::rotation_error_deg(estimate->T_1_2, T_1_2), 0.2);
  EXPECT_GE(estimate->num_inliers, 50);
  EXPECT_LE(estimate->num_inliers, 70);
  // Every correspondence flagged inlier is consistent with the truth.
  for (std::size_t i = 0; i < correspondences.size(); ++i) {
    if (estimate->inliers[i]) {
      EXPECT_TRUE(is_relative_pose_inlier(correspondences[i], T_1_2, camera(), 4 * 9.21));
    }
  }
}

TEST(EstimateRelativePose, SameSeedSameAnswer) {
  std::mt19937_64 rng(6);
  const SE3 T_1_2 = SE3::exp((Vec6d() << -0.1, 0.1, 0.3, -0.05, 0.1, 0.2).finished());
  const auto correspondences = make_correspondences(T_1_2, 80, 0.5, rng);
  RelativePoseRansacOptions options;
  options.seed = 99;
  const auto a = estimate_relative_pose(correspondences, camera(), options);
  const auto b = estimate_relative_pose(correspondences, camera(), options);
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->T_1_2.matrix(), b->T_1_2.matrix());
  EXPECT_EQ(a->inliers, b->inliers);
  EXPECT_EQ(a->iterations, b->iterations);
}

TEST(EstimateRelativePose, PureOutliersGiveNothing) {
  std::mt19937_64 rng(7);
  const auto correspondences = make_correspondences(SE3(), 60, 1.0, rng);
  EXPECT_FALSE(estimate_relative_pose(correspondences, camera(), {}));
}

}  // namespace
}  // namespace ddl::loop
