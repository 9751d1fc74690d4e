#pragma once
// Pose graph optimisation over SE(3) (RGB-D: metric scale is observed, so no Sim(3)), used by loop
// closing to spread the loop correction over the essential graph (ORB-SLAM2
// Optimizer::OptimizeEssentialGraph with scale fixed).
//
// Vertices are poses T_c_w. An edge (i, j) measures T_i_j = T_i_w * T_w_j (camera j expressed in
// camera i); its residual is the twist
//   e = log(T_i_j^-1 * T_i_w * T_j_w^-1) = [rho; phi]   (metres; radians)
// weighted by a 6x6 information matrix in that order (identity by default, like ORB-SLAM2's
// essential graph edges). At least one vertex must be fixed (the gauge; ORB-SLAM2 fixes the loop
// keyframe). Solved with Levenberg-Marquardt and a sparse Cholesky factorisation.
//
// Thread-safety: a pure function of its arguments; the abort flag may be set from any thread.

#include <cstddef>
#include <string>
#include <vector>

#include "ddl/core/se3.h"
#include "ddl/optimization/optimizer_config.h"
#include "ddl/optimization/types.h"

namespace ddl::optimization {

struct PoseGraphVertex {
  SE3 T_c_w;           ///< world -> camera
  bool fixed = false;  ///< held constant (returned bit-exactly)
};

struct PoseGraphEdge {
  std::size_t i = 0;  ///< index of the first vertex
  std::size_t j = 0;  ///< index of the second vertex (!= i)
  SE3 T_i_j;          ///< measured pose of camera j in camera i (T_i_w * T_j_w^-1)
  Mat6d information = Mat6d::Identity();  ///< symmetric positive definite, [rho; phi] order
};

struct PoseGraphProblem {
  std::vector<PoseGraphVertex> vertices;
  std::vector<PoseGraphEdge> edges;
};

struct PoseGraphResult {
  std::vector<SE3> T_c_w;     ///< corrected pose per vertex (fixed ones unchanged)
  bool aborted = false;       ///< the abort flag stopped the optimisation
  int iterations = 0;         ///< LM iterations run
  double initial_cost = 0.0;  ///< 0.5 sum of e^T Omega e before
  double final_cost = 0.0;    ///< and after
  std::string linear_solver;  ///< the Ceres linear solver used, for logs
};

/// Optimises the free vertices for config.pose_graph_iterations iterations at most. Throws
/// ddl::Error when no vertex is fixed, an edge index is out of range or i == j, or an information
/// matrix is not symmetric positive definite; ddl::ConfigError when config is invalid.
PoseGraphResult optimize_pose_graph(const PoseGraphProblem& problem, const OptimizerConfig& config,
                                    const SolveControl& control = {});

}  // namespace ddl::optimization
