#pragma once
// Settings of local mapping. Defaults are ORB-SLAM2's RGB-D LocalMapping thresholds (Mur-Artal &
// Tardos, T-RO 2017; ORB-SLAM T-RO 2015 section VI) and its TUM settings (bf = 40, ThDepth = 40).
// Keys in error messages are "mapping.<field>" ("mapping.optimizer.<field>" for the embedded BA
// schedule).

#include "ddl/optimization/optimizer_config.h"

namespace ddl::mapping {

/// New map points from matches between the new keyframe and its covisible keyframes
/// (ORB-SLAM2 LocalMapping::CreateNewMapPoints and ORBmatcher::SearchForTriangulation).
struct TriangulationConfig {
  int neighbours = 10;               // best covisible keyframes searched (RGB-D: 10)
  int max_hamming = 50;              // descriptor distance of a match at most (TH_LOW)
  double epipolar_chi2 = 3.84;       // squared distance to the epipolar line / sigma^2 (1 dof, 95%)
  double epipole_min_px = 10.0;      // mono-mono matches this close to the epipole are dropped
  bool check_orientation = false;    // rotation-consistency histogram (ORB-SLAM2: off here)
  double max_parallax_cos = 0.9998;  // rays more parallel than this are not triangulated (mono)
  double chi2_mono = 5.991;          // reprojection check, 2 dof
  double chi2_stereo = 7.8;          // reprojection check, 3 dof (u, v, u_right)
  double scale_consistency = 1.5;    // distance ratio vs octave ratio tolerance (x scale factor)
};

/// Fusion of duplicated points between the new keyframe and its neighbours
/// (ORB-SLAM2 LocalMapping::SearchInNeighbors and ORBmatcher::Fuse).
struct FusionConfig {
  int neighbours = 10;         // best covisibles of the new keyframe
  int second_neighbours = 5;   // best covisibles of each of those
  double radius_factor = 3.0;  // search window = radius_factor * scale of the predicted level
  int max_hamming = 50;        // descriptor distance of a fusion at most (TH_LOW)
  double chi2_mono = 5.991;    // reprojection check against the candidate keypoint, 2 dof
  double chi2_stereo = 7.8;    // ... 3 dof
  double min_view_cos = 0.5;   // points seen more than 60 degrees off their mean view are skipped
};

/// Recent map point culling (ORB-SLAM2 LocalMapping::MapPointCulling).
struct PointCullingConfig {
  double min_found_ratio = 0.25;  // found / visible below this: culled
  int max_observations = 3;       // culled when observed (stereo counting 2) at most this much...
  int observation_window = 2;     // ... this many keyframes after its creation (RGB-D: 3, 2)
  int probation_keyframes = 3;    // a point that survives this many keyframes is no longer recent
};

/// Redundant keyframe culling (ORB-SLAM2 LocalMapping::KeyFrameCulling).
struct KeyFrameCullingConfig {
  bool enabled = true;
  double redundant_ratio = 0.9;  // culled when more than this fraction of its close points...
  int min_other_observers = 3;   // ... are seen by at least this many other keyframes at the same
                                 // or a finer scale (level <= own level + 1)
};

struct LocalMapperConfig {
  double bf = 40.0;  // virtual stereo baseline times fx [m px]; must equal tracking.frame.bf
  double close_depth_baselines = 40.0;  // close points: depth < this * bf / fx (ThDepth)
  int bow_levels_up = 3;  // direct index levels above the words (must equal tracking's)
  TriangulationConfig triangulation;
  FusionConfig fusion;
  PointCullingConfig point_culling;
  KeyFrameCullingConfig keyframe_culling;
  bool local_ba = true;            // run local bundle adjustment
  int local_ba_min_keyframes = 3;  // ... once the map has at least this many keyframes
  /// Free keyframes of a local BA at most: the new keyframe and its strongest covisibles (the
  /// rest that see local points stay fixed). ORB-SLAM2 frees every covisible keyframe; when the
  /// map degenerates (a keyframe on every frame, all seeing the same points) that grows without
  /// bound. Real sequences stay below it (fr1_rpy: at most 54). 0 = no limit.
  int local_ba_max_keyframes = 60;
  optimization::OptimizerConfig optimizer;  // local BA schedule (local_ba, chi2_*, threads)

  /// Throws ddl::ConfigError naming the key ("mapping.triangulation.neighbours", ...).
  void validate() const;
};

}  // namespace ddl::mapping
