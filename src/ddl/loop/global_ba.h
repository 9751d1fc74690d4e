#pragma once
// Global bundle adjustment after a loop closure (ORB-SLAM2 LoopClosing::RunGlobalBundleAdjustment
// and Optimizer::GlobalBundleAdjustemnt). Split in two so that the solve can run in a background
// thread while tracking and local mapping go on:
//   - run_global_bundle_adjustment: snapshots every keyframe pose, point and observation (under
//     Map::read_consistent) and solves; the first keyframe is the gauge. The map is not touched.
//   - merge_global_bundle_adjustment: writes the result back (inside Map::apply_frame_change).
//     Keyframes created meanwhile are corrected through the spanning tree (each child keeps its
//     pose relative to its parent), points created meanwhile move with their reference keyframe.
// Thread-safety: run from any thread (a pure function of the snapshot); merge with local mapping
// kept still (ORB-SLAM2 stops it).

#include <atomic>
#include <map>

#include "ddl/core/se3.h"
#include "ddl/map/map.h"
#include "ddl/mapping/keyframe_geometry.h"
#include "ddl/optimization/optimizer_config.h"

namespace ddl::loop {

struct GlobalBaResult {
  std::map<map::KeyFrameId, SE3> T_c_w;       ///< optimised keyframe poses
  std::map<map::MapPointId, Vec3d> points_w;  ///< optimised point positions
  std::size_t observations = 0;
  int iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  bool aborted = false;  ///< the abort flag stopped it: do not merge
  bool failed = false;   ///< Ceres returned no usable solution: nothing to merge
};

GlobalBaResult run_global_bundle_adjustment(const map::Map& map,
                                            const mapping::CameraIntrinsics& camera,
                                            const optimization::OptimizerConfig& config,
                                            const std::atomic<bool>* abort = nullptr);

/// Returns the number of keyframes whose pose was set. A result none of whose keyframes is in
/// the map any more (a reset cleared it while the solve ran) changes nothing and announces no
/// correction: it returns 0.
std::size_t merge_global_bundle_adjustment(map::Map& map, const GlobalBaResult& result);

}  // namespace ddl::loop
