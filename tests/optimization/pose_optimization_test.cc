#include "ddl/optimization/pose_optimization.h"

#include <gtest/gtest.h>

#include <random>

#include "ddl/core/error.h"
#include "synthetic.h"

namespace ddl::optimization {
namespace {

using namespace testing;  // NOLINT: synthetic scene helpers

struct Scene {
  SE3 T_c_w_true;
  std::vector<PoseObservation> observations;
  std::vector<bool> is_outlier;
};

/// n points seen by a camera at a known pose; `stereo_fraction` of them with RGB-D residuals.
Scene make_scene(int n, double stereo_fraction, double noise_px, double outlier_fraction,
                 std::mt19937& rng) {
  const CameraIntrinsics cam = tum1_camera();
  Scene scene;
  scene.T_c_w_true =
      SE3(Mat3d(Eigen::AngleAxisd(0.4, Vec3d(0.2, 1.0, -0.3).normalized())), Vec3d(0.3, -0.1, 0.8));
  std::uniform_real_distribution<double> u(0.0, 1.0);
  std::uniform_int_distribution<int> level(0, kLevels - 1);
  for (int i = 0; i < n; ++i) {
    PoseObservation obs;
    obs.p_w = random_visible_point(cam, scene.T_c_w_true, 0.5, 6.0, rng);
    obs.measurement = measure(cam, scene.T_c_w_true, obs.p_w, u(rng) < stereo_fraction, level(rng));
    if (noise_px > 0.0) add_noise(&obs.measurement, noise_px, rng);
    const bool outlier = u(rng) < outlier_fraction;
    if (outlier) make_gross_outlier(cam, &obs.measurement, rng);
    scene.observations.push_back(obs);
    scene.is_outlier.push_back(outlier);
  }
  return scene;
}

TEST(PoseOptimization, ConvergesFromPerturbedPoseWithoutNoise) {
  std::mt19937 rng(1);
  const Scene scene = make_scene(300, 0.7, 0.0, 0.0, rng);
  for (int trial = 0; trial < 5; ++trial) {
    const SE3 initial = perturb(scene.T_c_w_true, 0.05, rad(3.0), rng);
    const PoseOptimizationResult r =
        optimize_pose(tum1_camera(), initial, scene.observations, OptimizerConfig{});
    ASSERT_TRUE(r.optimized);
    EXPECT_LT(translation_error(r.T_c_w, scene.T_c_w_true), 1e-3) << "trial " << trial;
    EXPECT_LT(deg(rotation_error(r.T_c_w, scene.T_c_w_true)), 0.05) << "trial " << trial;
    // Noise-free: the optimum is the truth to solver precision, and everything is an inlier.
    EXPECT_LT(translation_error(r.T_c_w, scene.T_c_w_true), 1e-7);
    EXPECT_EQ(r.num_inliers, 300);
    EXPECT_EQ(static_cast<int>(std::count(r.inliers.begin(), r.inliers.end(), true)), 300);
  }
}

TEST(PoseOptimization, RecoversPoseAndFlagsGrossOutliers) {
  std::mt19937 rng(2);
  for (int trial = 0; trial < 5; ++trial) {
    const Scene scene = make_scene(400, 0.7, 1.0, 0.2, rng);
    const SE3 initial = perturb(scene.T_c_w_true, 0.05, rad(3.0), rng);
    const PoseOptimizationResult r =
        optimize_pose(tum1_camera(), initial, scene.observations, OptimizerConfig{});
    ASSERT_TRUE(r.optimized);
    EXPECT_LT(translation_error(r.T_c_w, scene.T_c_w_true), 0.01) << "trial " << trial;
    EXPECT_LT(deg(rotation_error(r.T_c_w, scene.T_c_w_true)), 0.5) << "trial " << trial;

    int outliers = 0, flagged = 0, inliers = 0, kept = 0;
    for (std::size_t i = 0; i < scene.observations.size(); ++i) {
      if (scene.is_outlier[i]) {
        ++outliers;
        flagged += r.inliers[i] ? 0 : 1;
      } else {
        ++inliers;
        kept += r.inliers[i] ? 1 : 0;
      }
    }
    ASSERT_GT(outliers, 40);
    EXPECT_GE(flagged, 0.9 * outliers) << "trial " << trial;
    // 1 px noise against sigma = 1.2^level px: at most a few percent of good matches fail chi2.
    EXPECT_GE(kept, 0.9 * inliers) << "trial " << trial;
    EXPECT_EQ(r.num_inliers,
              static_cast<int>(std::count(r.inliers.begin(), r.inliers.end(), true)));
  }
}

TEST(PoseOptimization, MonocularOnlyObservationsAlsoConverge) {
  std::mt19937 rng(3);
  const Scene scene = make_scene(200, 0.0, 0.0, 0.0, rng);
  const SE3 initial = perturb(scene.T_c_w_true, 0.05, rad(3.0), rng);
  const PoseOptimizationResult r =
      optimize_pose(tum1_camera(), initial, scene.observations, OptimizerConfig{});
  EXPECT_LT(translation_error(r.T_c_w, scene.T_c_w_true), 1e-3);
  EXPECT_LT(deg(rotation_error(r.T_c_w, scene.T_c_w_true)), 0.05);
}

TEST(PoseOptimization, OutliersAreReclassifiedEachRound) {
  // A very poor start makes good matches look like outliers after round 1; because outliers are
  // re-classified after every round they come back once the pose has converged.
  std::mt19937 rng(4);
  const Scene scene = make_scene(200, 1.0, 0.0, 0.0, rng);
  const SE3 initial = perturb(scene.T_c_w_true, 0.3, rad(10.0), rng);
  OptimizerConfig one_round;
  one_round.pose_rounds = 1;
  one_round.pose_iterations_per_round = 1;
  const PoseOptimizationResult early =
      optimize_pose(tum1_camera(), initial, scene.observations, one_round);
  const PoseOptimizationResult full =
      optimize_pose(tum1_camera(), initial, scene.observations, OptimizerConfig{});
  EXPECT_LT(early.num_inliers, 200);
  EXPECT_EQ(full.num_inliers, 200);
  EXPECT_LT(translation_error(full.T_c_w, scene.T_c_w_true), 1e-6);
}

PosePrior prior_at(const SE3& T_c_w, double sigma_translation_m, double sigma_rotation_rad) {
  PosePrior prior;
  prior.T_c_w = T_c_w;
  prior.sqrt_information.diagonal() << Vec3d::Constant(1.0 / sigma_translation_m),
      Vec3d::Constant(1.0 / sigma_rotation_rad);
  return prior;
}

TEST(PoseOptimization, PriorBarelyMovesAWellConstrainedPose) {
  // 300 exact observations, most with depth, and a prior 2 cm and 0.5 deg off the truth with the
  // tracker's default sigmas (5 mm, 1 deg): the observations decide, the prior moves the pose by
  // well under a millimetre.
  std::mt19937 rng(7);
  const Scene scene = make_scene(300, 0.7, 0.0, 0.0, rng);
  const PosePrior prior = prior_at(perturb(scene.T_c_w_true, 0.02, rad(0.5), rng), 0.005, rad(1.0));
  const PoseOptimizationResult r =
      optimize_pose(tum1_camera(), prior.T_c_w, scene.observations, OptimizerConfig{}, &prior);
  ASSERT_TRUE(r.optimized);
  EXPECT_LT(translation_error(r.T_c_w, scene.T_c_w_true), 1e-3);
  EXPECT_LT(deg(rotation_error(r.T_c_w, scene.T_c_w_true)), 0.05);
  EXPECT_EQ(r.num_inliers, 300);
}

TEST(PoseOptimization, PriorHoldsAPoseTheObservationsHardlyConstrain) {
  // Only distant points (40-60 m) without depth, with 1 px noise: rotation is observable,
  // translation hardly (a centimetre moves them by a tenth of a pixel). Without the prior the
  // noise throws the position off by far more than the prior's sigma; with it the position stays
  // within it.
  std::mt19937 rng(8);
  const CameraIntrinsics cam = tum1_camera();
  const SE3 T_true = SE3(Mat3d(Eigen::AngleAxisd(0.3, Vec3d::UnitY())), Vec3d(0.1, 0.0, 0.2));
  std::vector<PoseObservation> observations;
  std::uniform_int_distribution<int> level(0, 2);
  for (int i = 0; i < 150; ++i) {
    PoseObservation obs;
    obs.p_w = random_visible_point(cam, T_true, 40.0, 60.0, rng);
    obs.measurement = measure(cam, T_true, obs.p_w, false, level(rng));
    add_noise(&obs.measurement, 1.0, rng);
    observations.push_back(obs);
  }
  const SE3 initial = perturb(T_true, 0.005, rad(0.5), rng);
  const PoseOptimizationResult free = optimize_pose(cam, initial, observations, OptimizerConfig{});
  const PosePrior prior = prior_at(T_true, 0.005, rad(1.0));
  const PoseOptimizationResult held =
      optimize_pose(cam, initial, observations, OptimizerConfig{}, &prior);
  ASSERT_TRUE(free.optimized);
  ASSERT_TRUE(held.optimized);
  EXPECT_GT(translation_error(free.T_c_w, T_true), 0.03);
  EXPECT_LT(translation_error(held.T_c_w, T_true), 0.01);
  // The rotation, which the points do fix, is found either way.
  EXPECT_LT(deg(rotation_error(free.T_c_w, T_true)), 0.1);
  EXPECT_LT(deg(rotation_error(held.T_c_w, T_true)), 0.1);
}

TEST(PoseOptimization, TooFewObservationsLeavePoseUnchanged) {
  std::mt19937 rng(5);
  const Scene scene = make_scene(2, 1.0, 0.0, 0.0, rng);
  const SE3 initial = perturb(scene.T_c_w_true, 0.05, rad(3.0), rng);
  const PoseOptimizationResult r =
      optimize_pose(tum1_camera(), initial, scene.observations, OptimizerConfig{});
  EXPECT_FALSE(r.optimized);
  EXPECT_EQ(r.num_inliers, 0);
  EXPECT_EQ(r.inliers.size(), 2u);
  EXPECT_EQ(r.T_c_w.matrix(), initial.matrix());
}

TEST(PoseOptimization, FewObservationsRunOneRound) {
  std::mt19937 rng(6);
  const Scene scene = make_scene(8, 1.0, 0.0, 0.0, rng);
  const SE3 initial = perturb(scene.T_c_w_true, 0.02, rad(1.0), rng);
  const OptimizerConfig config;
  const PoseOptimizationResult r =
      optimize_pose(tum1_camera(), initial, scene.observations, config);
  ASSERT_TRUE(r.optimized);
  EXPECT_LE(r.iterations, config.pose_iterations_per_round);
  EXPECT_EQ(r.num_inliers, 8);
  EXPECT_LT(translation_error(r.T_c_w, scene.T_c_w_true), 1e-3);
}

TEST(PoseOptimization, RejectsMalformedInput) {
  std::mt19937 rng(7);
  Scene scene = make_scene(20, 1.0, 0.0, 0.0, rng);
  scene.observations[5].measurement.inv_sigma2 = 0.0;
  try {
    optimize_pose(tum1_camera(), scene.T_c_w_true, scene.observations, OptimizerConfig{});
    FAIL() << "expected ddl::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("observation 5"), std::string::npos) << e.what();
    EXPECT_NE(std::string(e.what()).find("inv_sigma2"), std::string::npos) << e.what();
  }
  scene.observations[5].measurement.inv_sigma2 = 1.0;
  CameraIntrinsics no_baseline = tum1_camera();
  no_baseline.bf = 0.0;
  EXPECT_THROW(optimize_pose(no_baseline, scene.T_c_w_true, scene.observations, OptimizerConfig{}),
               Error);
  OptimizerConfig bad;
  bad.pose_rounds = 0;
  EXPECT_THROW(optimize_pose(tum1_camera(), scene.T_c_w_true, scene.observations, bad),
               ConfigError);
  PosePrior nan_prior;
  nan_prior.sqrt_information(2, 2) = std::nan("");
  EXPECT_THROW(optimize_pose(tum1_camera(), scene.T_c_w_true, scene.observations, OptimizerConfig{},
                             &nan_prior),
               Error);
}

}  // namespace
}  // namespace ddl::optimization
