#pragma once
// Local bundle adjustment of the new keyframe's neighbourhood (ORB-SLAM2
// Optimizer::LocalBundleAdjustment; ORB-SLAM T-RO 2015 section VI-D): the new keyframe and every
// keyframe covisible with it are optimised together with all the points they see; keyframes that
// see those points but are not covisible with the new one are held fixed. Observations classified
// as outliers afterwards are erased from the map, then poses and points are written back inside
// Map::apply_update so that tracking never sees half an update.
// Thread-safety: any thread; local mapping runs it on the keyframe it is processing.

#include <atomic>
#include <cstddef>

#include "ddl/map/keyframe.h"
#include "ddl/map/map.h"
#include "ddl/mapping/keyframe_geometry.h"
#include "ddl/optimization/optimizer_config.h"

namespace ddl::mapping {

struct LocalBaStatistics {
  std::size_t free_keyframes = 0;
  std::size_t fixed_keyframes = 0;
  std::size_t points = 0;
  std::size_t observations = 0;
  std::size_t outliers_erased = 0;  // keyframe-point associations removed
  int iterations = 0;
  double initial_cost = 0.0;
  double final_cost = 0.0;
  bool aborted = false;  // the abort flag stopped the solve (its estimate was still applied)
  bool ran = false;      // false: nothing to optimise, or aborted before starting
};

/// Runs local BA around `current`. `abort` (may be null) is polled by the solver after every
/// iteration; when it is already set on entry nothing runs. `max_free_keyframes` > 0 frees only
/// `current` and its strongest covisibles up to that many keyframes in all.
LocalBaStatistics run_local_bundle_adjustment(const map::KeyFramePtr& current, map::Map& map,
                                              const CameraIntrinsics& camera,
                                              const optimization::OptimizerConfig& config,
                                              const std::atomic<bool>* abort = nullptr,
                                              std::size_t max_free_keyframes = 0);

}  // namespace ddl::mapping
