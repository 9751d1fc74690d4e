#include "ddl/optimization/optimizer_config.h"

#include <gtest/gtest.h>

#include <functional>

#include "config_error_check.h"
#include "ddl/core/error.h"
#include "ddl/optimization/types.h"

namespace ddl::optimization {
namespace {

using test_support::throws_config_error_for_key;

TEST(OptimizerConfig, DefaultsAreValidAndFollowOrbSlam2) {
  const OptimizerConfig config;
  EXPECT_NO_THROW(config.validate());
  EXPECT_EQ(config.num_threads, 1);
  EXPECT_DOUBLE_EQ(config.chi2_mono, 5.991);
  EXPECT_DOUBLE_EQ(config.chi2_stereo, 7.815);
  EXPECT_EQ(config.pose_rounds, 4);
  EXPECT_EQ(config.pose_iterations_per_round, 10);
  EXPECT_EQ(config.local_ba.initial_iterations, 5);
  EXPECT_EQ(config.local_ba.refine_iterations, 10);
  EXPECT_TRUE(config.local_ba.remove_outliers);
}

TEST(OptimizerConfig, ValidateNamesTheBadKey) {
  auto with = [](auto mutate) {
    return [mutate] {
      OptimizerConfig c;
      mutate(c);
      c.validate();
    };
  };
  EXPECT_TRUE(throws_config_error_for_key(with([](OptimizerConfig& c) { c.num_threads = 0; }),
                                          "optimizer.num_threads"));
  EXPECT_TRUE(throws_config_error_for_key(with([](OptimizerConfig& c) { c.chi2_mono = -1.0; }),
                                          "optimizer.chi2_mono"));
  EXPECT_TRUE(throws_config_error_for_key(with([](OptimizerConfig& c) { c.chi2_stereo = NAN; }),
                                          "optimizer.chi2_stereo"));
  EXPECT_TRUE(
      throws_config_error_for_key(with([](OptimizerConfig& c) { c.pose_iterations_per_round = 0; }),
                                  "optimizer.pose_iterations_per_round"));
  EXPECT_TRUE(throws_config_error_for_key(
      with([](OptimizerConfig& c) { c.local_ba.initial_iterations = 0; }),
      "optimizer.local_ba.initial_iterations"));
  EXPECT_TRUE(throws_config_error_for_key(
      with([](OptimizerConfig& c) { c.global_ba.refine_iterations = -1; }),
      "optimizer.global_ba.refine_iterations"));
  EXPECT_TRUE(
      throws_config_error_for_key(with([](OptimizerConfig& c) { c.pose_graph_iterations = 0; }),
                                  "optimizer.pose_graph_iterations"));
}

TEST(OptimizerConfig, LinearSolverNamesRoundTrip) {
  for (BaLinearSolver s : {BaLinearSolver::kAuto, BaLinearSolver::kDenseSchur,
                           BaLinearSolver::kSparseSchur, BaLinearSolver::kIterativeSchur}) {
    EXPECT_EQ(ba_linear_solver_from_string(to_string(s)), s);
  }
  EXPECT_TRUE(throws_config_error_for_key([] { ba_linear_solver_from_string("qr"); },
                                          "optimizer.ba_linear_solver"));
}

TEST(CameraIntrinsics, ValidateNamesTheBadKey) {
  CameraIntrinsics cam{500.0, 500.0, 320.0, 240.0, 40.0};
  EXPECT_NO_THROW(cam.validate());
  cam.fy = 0.0;
  EXPECT_TRUE(throws_config_error_for_key([&] { cam.validate(); }, "camera.fy"));
  cam.fy = 500.0;
  cam.bf = -1.0;
  EXPECT_TRUE(throws_config_error_for_key([&] { cam.validate(); }, "camera.bf"));
}

}  // namespace
}  // namespace ddl::optimization
