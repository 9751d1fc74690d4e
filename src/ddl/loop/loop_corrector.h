#pragma once
// Loop correction (ORB-SLAM2 LoopClosing::CorrectLoop with the scale fixed; ORB-SLAM T-RO 2015
// section VII-C):
//   1. the current keyframe takes the pose the verification estimated and its covisible keyframes
//      move rigidly with it; their map points follow the keyframe that sees them;
//   2. loop fusion: the current keyframe's matches with the loop points replace its own points,
//      and the loop points are fused into every corrected keyframe at its corrected pose;
//   3. the covisibility of the corrected keyframes is updated; the links that appear across the
//      loop feed the essential graph, which is optimised (essential_graph.h);
//   4. a loop edge joins the current and the loop keyframe; Map::notify_big_change().
// The caller keeps local mapping still meanwhile (ORB-SLAM2 stops it); map changes of steps 1-2
// and the pose graph write-back run inside Map::apply_frame_change.
// Thread-safety: any thread, one correction at a time.

#include <cstddef>

#include "ddl/loop/essential_graph.h"
#include "ddl/loop/loop_closer_config.h"
#include "ddl/loop/loop_verification.h"
#include "ddl/map/map.h"
#include "ddl/mapping/keyframe_geometry.h"

namespace ddl::loop {

struct LoopCorrectionStatistics {
  std::size_t corrected_keyframes = 0;  // the current keyframe and its covisibles
  std::size_t corrected_points = 0;
  std::size_t replaced_points = 0;  // current keyframe points replaced by loop points
  int fused_points = 0;             // loop points fused into the corrected keyframes
  std::size_t loop_links = 0;       // new covisibility links across the loop
  EssentialGraphStatistics essential_graph;
};

LoopCorrectionStatistics correct_loop(const map::KeyFramePtr& current, const LoopMatch& loop,
                                      map::Map& map, const mapping::CameraIntrinsics& camera,
                                      const LoopCorrectionConfig& config,
                                      const optimization::OptimizerConfig& optimizer);

}  // namespace ddl::loop
