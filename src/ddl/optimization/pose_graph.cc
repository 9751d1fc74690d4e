#include "ddl/optimization/pose_graph.h"

#include <ceres/problem.h>
#include <ceres/solver.h>
#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <Eigen/Cholesky>

#include "ddl/core/error.h"
#include "ddl/optimization/cost_functions.h"
#include "ddl/optimization/se3_manifold.h"
#include "ddl/optimization/solver_support.h"

namespace ddl::optimization {
namespace {

/// L^T with L L^T = information, so that |L^T e|^2 = e^T information e.
Mat6d sqrt_information(const Mat6d& information, std::size_t edge) {
  if (!information.allFinite() || (information - information.transpose()).cwiseAbs().maxCoeff() >
                                      1e-9 * (1.0 + information.cwiseAbs().maxCoeff())) {
    throw Error(
        fmt::format("pose graph edge {}: information matrix is not finite and symmetric", edge));
  }
  const Eigen::LLT<Mat6d> llt(information);
  if (llt.info() != Eigen::Success) {
    throw Error(
        fmt::format("pose graph edge {}: information matrix is not positive definite", edge));
  }
  return llt.matrixU();
}

}  // namespace

PoseGraphResult optimize_pose_graph(const PoseGraphProblem& problem, const OptimizerConfig& config,
                                    const SolveControl& control) {
  config.validate();
  const std::size_t num_v = problem.vertices.size();
  PoseGraphResult result;
  result.T_c_w.reserve(num_v);
  bool any_fixed = false;
  for (std::size_t v = 0; v < num_v; ++v) {
    const SE3& T = problem.vertices[v].T_c_w;
    if (!T.quaternion().coeffs().allFinite() || !T.translation().allFinite()) {
      throw Error(fmt::format("pose graph vertex {}: pose is not finite", v));
    }
    any_fixed = any_fixed || problem.vertices[v].fixed;
    result.T_c_w.push_back(T);
  }
  if (num_v > 0 && !any_fixed) {
    throw Error("pose graph: no vertex is fixed (fix at least one, e.g. the loop keyframe)");
  }
  std::vector<Mat6d> sqrt_infos;
  sqrt_infos.reserve(problem.edges.size());
  for (std::size_t e = 0; e < problem.edges.size(); ++e) {
    const PoseGraphEdge& edge = problem.edges[e];
    if (edge.i >= num_v || edge.j >= num_v || edge.i == edge.j) {
      throw Error(fmt::format("pose graph edge {}: vertices ({}, {}) invalid for {} vertices", e,
                              edge.i, edge.j, num_v));
    }
    if (!edge.T_i_j.quaternion().coeffs().allFinite() || !edge.T_i_j.translation().allFinite()) {
      throw Error(fmt::format("pose graph edge {}: measurement is not finite", e));
    }
    sqrt_infos.push_back(sqrt_information(edge.information, e));
  }

  std::vector<PoseParameters> poses(num_v);
  for (std::size_t v = 0; v < num_v; ++v) poses[v] = to_parameters(problem.vertices[v].T_c_w);
  SE3Manifold manifold;
  ceres::Problem::Options problem_options;
  problem_options.manifold_ownership = ceres::DO_NOT_TAKE_OWNERSHIP;
  ceres::Problem ceres_problem(problem_options);
  int free_vertices = 0;
  bool gauge_held = false;  // a fixed vertex takes part in some edge
  for (std::size_t e = 0; e < problem.edges.size(); ++e) {
    const PoseGraphEdge& edge = problem.edges[e];
    if (problem.vertices[edge.i].fixed && problem.vertices[edge.j].fixed) continue;
    for (std::size_t v : {edge.i, edge.j}) {
      if (ceres_problem.HasParameterBlock(poses[v].data())) continue;
      ceres_problem.AddParameterBlock(poses[v].data(), kPoseAmbientSize, &manifold);
      if (problem.vertices[v].fixed) {
        ceres_problem.SetParameterBlockConstant(poses[v].data());
        gauge_held = true;
      } else {
        ++free_vertices;
      }
    }
    ceres_problem.AddResidualBlock(new PoseGraphEdgeCost(edge.T_i_j, sqrt_infos[e]), nullptr,
                                   poses[edge.i].data(), poses[edge.j].data());
  }
  if (free_vertices == 0) return result;
  if (!gauge_held) {
    throw Error(
        "pose graph: no fixed vertex has an edge to a free one, so the gauge is free (fix a "
        "vertex of the graph, e.g. the loop keyframe)");
  }

  ceres::Solver::Options options =
      detail::base_options(config.num_threads, config.pose_graph_iterations);
  if (const auto sparse = detail::best_sparse_library()) {
    options.linear_solver_type = ceres::SPARSE_NORMAL_CHOLESKY;
    options.sparse_linear_algebra_library_type = *sparse;
  } else {
    options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
  }
  result.linear_solver = ceres::LinearSolverTypeToString(options.linear_solver_type);
  detail::ControlCallback callback(control);
  options.callbacks.push_back(&callback);
  ceres::Solver::Summary summary;
  ceres::Solve(options, &ceres_problem, &summary);
  detail::solution_usable(summary, "pose graph");
  result.aborted = callback.aborted();
  result.iterations = detail::iterations_run(summary);
  result.initial_cost = summary.initial_cost;
  result.final_cost = summary.final_cost;
  for (std::size_t v = 0; v < num_v; ++v) {
    if (!problem.vertices[v].fixed && ceres_problem.HasParameterBlock(poses[v].data())) {
      result.T_c_w[v] = from_parameters(poses[v].data());
    }
  }
  spdlog::debug(
      "pose graph: {} vertices ({} free), {} edges, {} iterations, cost {:.4g} -> {:.4g}{}", num_v,
      free_vertices, problem.edges.size(), result.iterations, result.initial_cost,
      result.final_cost, result.aborted ? ", aborted" : "");
  return result;
}

}  // namespace ddl::optimization
