#pragma once
// Pose graph optimisation over the essential graph after a loop correction (ORB-SLAM2
// Optimizer::OptimizeEssentialGraph with the scale fixed; ORB-SLAM T-RO 2015 section VII-D).
// Vertices: every keyframe, starting at its corrected pose where the loop correction gave one;
// the loop keyframe is fixed. Edges (relative poses measured before the correction, so that the
// loop error spreads along them): the new loop links of the corrected neighbourhood (only strong
// ones except current-loop keyframe), the spanning tree, earlier loop edges and strong
// covisibility links (weight >= min_weight). Afterwards every map point moves with its reference
// keyframe (or with the keyframe that corrected it).
// Thread-safety: any thread; the write-back runs inside Map::apply_frame_change.

#include <map>
#include <set>

#include "ddl/core/se3.h"
#include "ddl/map/keyframe.h"
#include "ddl/map/map.h"
#include "ddl/optimization/optimizer_config.h"

namespace ddl::loop {

struct EssentialGraphInput {
  map::KeyFramePtr loop_keyframe;     ///< held fixed
  map::KeyFramePtr current_keyframe;  ///< its link to the loop keyframe is always an edge
  std::map<map::KeyFrameId, SE3> non_corrected_T_c_w;  ///< poses before the loop correction
  std::map<map::KeyFrameId, SE3> corrected_T_c_w;      ///< poses the correction gave
  /// New covisibility links of the corrected keyframes across the loop.
  std::map<map::KeyFrameId, std::set<map::KeyFrameId>> loop_connections;
  /// Map points the correction moved, with the keyframe whose correction moved them.
  std::map<map::MapPointId, map::KeyFrameId> corrected_points;
  int min_weight = 100;
};

struct EssentialGraphStatistics {
  std::size_t vertices = 0;
  std::size_t edges = 0;
  int iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
};

/// Optimises and writes poses and points back into `map`.
EssentialGraphStatistics optimize_essential_graph(map::Map& map, const EssentialGraphInput& input,
                                                  const optimization::OptimizerConfig& config);

}  // namespace ddl::loop
