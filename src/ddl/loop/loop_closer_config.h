#pragma once
// Settings of loop closing. Defaults are ORB-SLAM2's LoopClosing thresholds (Mur-Artal & Tardos,
// T-RO 2017; ORB-SLAM T-RO 2015 section VII) with the scale fixed (RGB-D: SE(3) instead of
// Sim(3)). Keys in error messages are "loop.<field>" ("loop.optimizer.<field>" for the embedded
// optimisation settings).

#include <cstdint>

#include "ddl/optimization/optimizer_config.h"

namespace ddl::loop {

/// Loop candidates from the keyframe database (ORB-SLAM2 LoopClosing::DetectLoop and
/// KeyFrameDatabase::DetectLoopCandidates).
struct LoopDetectionConfig {
  int min_keyframes_between_loops = 10;  // no detection until this many keyframes after the last
                                         // loop (and after the first keyframe)
  double min_common_words_ratio = 0.8;   // candidates share more than this * the best's words
  int score_covisibles = 10;             // best covisibles whose scores add to a candidate's
  double min_group_score_ratio = 0.75;   // groups scoring more than this * the best group's
  int consistency_threshold = 3;  // consecutive earlier keyframes whose candidate groups must agree
                                  // (0: every candidate goes to verification at once)
  int covisible_confirmations = 2;  // a candidate not consistent yet is accepted when its verified
                                    // loop also holds in this many best covisibles of the keyframe
                                    // (ORB-SLAM3; sparse RGB-D keyframes; 0: off)
};

/// Geometric verification of the candidates (ORB-SLAM2 LoopClosing::ComputeSim3 with the scale
/// fixed: 3D-3D RANSAC with Horn's closed form, then matches by projection and pose refinement).
struct LoopVerificationConfig {
  float bow_ratio = 0.75f;  // Lowe ratio of the BoW matching against a candidate
  /// Descriptor distance of a loop match: below it in the BoW search (ORB-SLAM2's TH_LOW test),
  /// at most it in the projection searches.
  int max_hamming = 50;
  bool check_orientation = true;         // rotation-consistency histogram on the BoW matches
  int min_bow_matches = 20;              // fewer BoW matches: the candidate is dropped
  int ransac_max_iterations = 300;       // RANSAC hypotheses per candidate at most
  double ransac_probability = 0.99;      // stop once an all-inlier sample was drawn this surely
  int ransac_min_inliers = 20;           // the RANSAC model needs this many inliers
  double ransac_chi2 = 9.21;             // inlier: reprojection error^2 < chi2 sigma^2 both ways
  std::uint64_t seed = 1;                // RANSAC random seed (combined with the keyframe ids)
  double candidate_search_radius = 7.5;  // projection search of the candidate's points (x scale)
  int min_refined_inliers = 20;          // inliers of the refined pose needed
  double loop_search_radius = 10.0;      // projection search of all loop points (x scale)
  int min_loop_matches = 40;             // matches with the loop points needed to accept
  int min_confirmation_inliers = 30;     // a covisible confirms a loop with this many inliers
};

/// Loop correction (ORB-SLAM2 LoopClosing::CorrectLoop and Optimizer::OptimizeEssentialGraph).
struct LoopCorrectionConfig {
  double fuse_radius = 4.0;              // loop point fusion window (x scale factor of the level)
  int fuse_max_hamming = 50;             // descriptor distance of a fusion at most
  int essential_graph_min_weight = 100;  // covisibility edges of the essential graph
};

struct LoopCloserConfig {
  bool enabled = true;  // false: process() does nothing
  double bf = 40.0;     // virtual stereo baseline times fx [m px]; must equal tracking.frame.bf
  LoopDetectionConfig detection;
  LoopVerificationConfig verification;
  LoopCorrectionConfig correction;
  bool global_ba = true;                    // global BA after every loop correction
  bool global_ba_in_background = false;     // run it in the closer's own thread; a run sets it
                                            // from `mode` (threaded: true), whatever is here
  optimization::OptimizerConfig optimizer;  // pose refinement, pose graph, global BA schedules

  /// Throws ddl::ConfigError naming the key ("loop.detection.consistency_threshold", ...).
  void validate() const;
};

}  // namespace ddl::loop
