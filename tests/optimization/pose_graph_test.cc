#include "ddl/optimization/pose_graph.h"

#include <gtest/gtest.h>

#include <atomic>
#include <random>

#include "ddl/core/error.h"
#include "synthetic.h"

namespace ddl::optimization {
namespace {

using namespace testing;  // NOLINT: synthetic scene helpers

/// n camera poses (T_c_w) on a circle of radius 3 m, looking at its centre, with some height
/// variation: a loop.
std::vector<SE3> circle_trajectory(int n) {
  std::vector<SE3> T_c_w;
  for (int k = 0; k < n; ++k) {
    const double a = 2.0 * M_PI * k / n;
    const Vec3d position(3.0 * std::cos(a), 0.3 * std::sin(3.0 * a), 3.0 * std::sin(a));
    const Vec3d z = (-position).normalized();  // optical axis towards the centre
    const Vec3d x = Vec3d::UnitY().cross(z).normalized();
    Mat3d R_w_c;
    R_w_c << x, z.cross(x), z;
    T_c_w.push_back(SE3(R_w_c, position).inverse());
  }
  return T_c_w;
}

struct LoopProblem {
  std::vector<SE3> truth;
  PoseGraphProblem problem;
};

/// Odometry edges k -> k+1 and one loop edge (n-1) -> 0. `odometry_error` spoils every odometry
/// measurement by the same small motion (a systematic drift); the initial estimate chains the
/// measured odometry from vertex 0 (fixed at the truth), so it drifts by construction.
LoopProblem make_loop(int n, const SE3& odometry_error, const Mat6d& loop_information) {
  LoopProblem lp;
  lp.truth = circle_trajectory(n);
  auto relative = [&](int i, int j) { return lp.truth[i] * lp.truth[j].inverse(); };
  for (int k = 0; k + 1 < n; ++k) {
    lp.problem.edges.push_back({static_cast<std::size_t>(k), static_cast<std::size_t>(k + 1),
                                odometry_error * relative(k, k + 1)});
  }
  lp.problem.edges.push_back(
      {static_cast<std::size_t>(n - 1), 0, relative(n - 1, 0), loop_information});
  SE3 T = lp.truth[0];
  lp.problem.vertices.push_back({T, true});
  for (int k = 1; k < n; ++k) {
    // T_{k,w} = T_{k,k-1} T_{k-1,w} with T_{k,k-1} = T_{k-1,k}^-1 measured.
    T = lp.problem.edges[k - 1].T_i_j.inverse() * T;
    lp.problem.vertices.push_back({T, false});
  }
  return lp;
}

double max_position_error(const std::vector<SE3>& a, const std::vector<SE3>& b) {
  double e = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) e = std::max(e, translation_error(a[k], b[k]));
  return e;
}
double max_rotation_error(const std::vector<SE3>& a, const std::vector<SE3>& b) {
  double e = 0.0;
  for (std::size_t k = 0; k < a.size(); ++k) e = std::max(e, rotation_error(a[k], b[k]));
  return e;
}

std::vector<SE3> vertex_poses(const PoseGraphProblem& p) {
  std::vector<SE3> out;
  for (const PoseGraphVertex& v : p.vertices) out.push_back(v.T_c_w);
  return out;
}

TEST(PoseGraph, ConsistentEdgesRecoverTruthFromDriftedStart) {
  // Exact odometry and loop measurements, drifted initial estimate (1 cm and 0.5 deg of error
  // compounded at every step): the unique optimum is the truth.
  const int n = 30;
  LoopProblem lp = make_loop(n, SE3(), Mat6d::Identity());
  const SE3 step_error(Mat3d(Eigen::AngleAxisd(rad(0.5), Vec3d::UnitY())), Vec3d(0.01, 0.0, 0.0));
  for (int k = 1; k < n; ++k) {
    lp.problem.vertices[k].T_c_w =
        lp.problem.edges[k - 1].T_i_j.inverse() * step_error * lp.problem.vertices[k - 1].T_c_w;
  }
  const std::vector<SE3> initial = vertex_poses(lp.problem);
  ASSERT_GT(max_position_error(initial, lp.truth), 0.3);
  const PoseGraphResult r = optimize_pose_graph(lp.problem, OptimizerConfig{});
  EXPECT_LT(max_position_error(r.T_c_w, lp.truth), 1e-6);
  EXPECT_LT(max_rotation_error(r.T_c_w, lp.truth), 1e-6);
  EXPECT_EQ(r.T_c_w[0].matrix(), lp.problem.vertices[0].T_c_w.matrix());
  EXPECT_FALSE(r.aborted);
}

TEST(PoseGraph, LoopEdgeSpreadsAccumulatedDrift) {
  // Biased odometry (0.3 deg yaw and 5 mm per step): the chained estimate ends far from the start;
  // a strong loop edge pulls the loop shut and the error is spread over all vertices.
  const int n = 30;
  const SE3 bias(Mat3d(Eigen::AngleAxisd(rad(0.3), Vec3d::UnitY())), Vec3d(0.005, 0.0, 0.0));
  Mat6d loop_information = 1e4 * Mat6d::Identity();
  LoopProblem lp = make_loop(n, bias, loop_information);
  const std::vector<SE3> initial = vertex_poses(lp.problem);
  const double before = max_position_error(initial, lp.truth);
  const PoseGraphResult r = optimize_pose_graph(lp.problem, OptimizerConfig{});
  const double after = max_position_error(r.T_c_w, lp.truth);
  EXPECT_LT(after, 0.3 * before) << "before " << before << " after " << after;
  EXPECT_LT(max_rotation_error(r.T_c_w, lp.truth), 0.3 * max_rotation_error(initial, lp.truth));
  // The strongly weighted loop edge is closed: last-to-first relative pose as measured.
  const PoseGraphEdge& loop = lp.problem.edges.back();
  const SE3 closure = loop.T_i_j.inverse() * r.T_c_w[n - 1] * r.T_c_w[0].inverse();
  EXPECT_LT(closure.translation().norm(), 2e-3);
  EXPECT_LT(closure.rotation_angle(), rad(0.1));
  EXPECT_LT(r.final_cost, 0.05 * r.initial_cost);
}

TEST(PoseGraph, AbortFlagStopsEarly) {
  const int n = 30;
  LoopProblem lp =
      make_loop(n, SE3(Mat3d(Eigen::AngleAxisd(rad(0.3), Vec3d::UnitY())), Vec3d(0.005, 0.0, 0.0)),
                Mat6d::Identity());
  std::atomic<bool> abort{false};
  int calls = 0;
  SolveControl control;
  control.abort = &abort;
  control.on_iteration = [&](int iteration, double) {
    ++calls;
    if (iteration == 1) abort.store(true);
  };
  const PoseGraphResult r = optimize_pose_graph(lp.problem, OptimizerConfig{}, control);
  EXPECT_TRUE(r.aborted);
  EXPECT_EQ(r.iterations, 1);
  EXPECT_EQ(calls, 2);
}

TEST(PoseGraph, RejectsUnanchoredGraphAndBadEdges) {
  LoopProblem lp = make_loop(5, SE3(), Mat6d::Identity());
  PoseGraphProblem unanchored = lp.problem;
  unanchored.vertices[0].fixed = false;
  EXPECT_THROW(optimize_pose_graph(unanchored, OptimizerConfig{}), Error);
  // A fixed vertex without edges holds nothing: the free vertices' gauge stays free.
  PoseGraphProblem fixed_apart = unanchored;
  fixed_apart.vertices.push_back({SE3(), true});
  try {
    optimize_pose_graph(fixed_apart, OptimizerConfig{});
    FAIL() << "expected ddl::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("gauge"), std::string::npos) << e.what();
  }
  PoseGraphProblem bad_index = lp.problem;
  bad_index.edges[2].j = 5;
  EXPECT_THROW(optimize_pose_graph(bad_index, OptimizerConfig{}), Error);
  PoseGraphProblem bad_info = lp.problem;
  bad_info.edges[1].information(0, 0) = -1.0;
  try {
    optimize_pose_graph(bad_info, OptimizerConfig{});
    FAIL() << "expected ddl::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("edge 1"), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace ddl::optimization
