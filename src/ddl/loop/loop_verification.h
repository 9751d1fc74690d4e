#pragma once
// Geometric verification of loop candidates (ORB-SLAM2 LoopClosing::ComputeSim3 with the scale
// fixed; ORB-SLAM T-RO 2015 section VII-B). For each candidate in turn:
//   1. BoW matches between the keyframe's map points and the candidate's (>= min_bow_matches);
//   2. relative pose by 3D-3D RANSAC (relative_pose.h) on those matches;
//   3. more matches by projecting the candidate's points at the estimated pose, then a pose-only
//      refinement (optimization::optimize_pose) of the keyframe against the candidate's points
//      (>= min_refined_inliers inliers);
//   4. matches with every point of the candidate and its covisibles (the loop points) by
//      projection at the refined pose (>= min_loop_matches), a last refinement drops outliers.
// The first candidate passing all steps is the loop.
// Thread-safety: any thread; reads entities through their locked methods.

#include <optional>
#include <vector>

#include "ddl/loop/loop_closer_config.h"
#include "ddl/map/keyframe.h"
#include "ddl/mapping/keyframe_geometry.h"

namespace ddl::loop {

struct LoopMatch {
  map::KeyFramePtr matched;  ///< the loop keyframe
  SE3 T_cur_matched;         ///< camera of the matched keyframe in the current camera
  SE3 T_cur_w_corrected;     ///< current pose consistent with the matched side of the map
  /// One slot per feature of the current keyframe: the loop point it matched, or null.
  std::vector<map::MapPointPtr> current_matches;
  std::vector<map::KeyFramePtr> loop_keyframes;  ///< the matched keyframe and its covisibles
  std::vector<map::MapPointPtr> loop_points;     ///< their points (ascending id)
  int bow_matches = 0;
  int ransac_inliers = 0;
  int refined_inliers = 0;
  int loop_matches = 0;  ///< matches with the loop points that survive the last refinement
};

/// Confirms a verified `loop` of `current` in `neighbour`, a covisible keyframe of `current`
/// (ORB-SLAM3's verification in the covisibility graph, Campos et al., T-RO 2021, section VI-A):
/// the loop points are projected into `neighbour` at the pose the loop implies for it (its
/// pose relative to `current` kept), matched as in step 4, and the pose refined. Loop points the
/// neighbour observes already are left out. Returns the inliers of the refinement (0 when it
/// fails).
int confirm_loop_in(const map::KeyFramePtr& neighbour, const map::KeyFramePtr& current,
                    const LoopMatch& loop, const mapping::CameraIntrinsics& camera,
                    const LoopVerificationConfig& config,
                    const optimization::OptimizerConfig& optimizer);

/// Verifies `candidates` in order against `current`; returns the first that passes.
std::optional<LoopMatch> verify_loop_candidates(const map::KeyFramePtr& current,
                                                const std::vector<map::KeyFramePtr>& candidates,
                                                const mapping::CameraIntrinsics& camera,
                                                const LoopVerificationConfig& config,
                                                const optimization::OptimizerConfig& optimizer);

}  // namespace ddl::loop
