#pragma once
// Settings of RGB-D tracking. Defaults are ORB-SLAM2's RGB-D tracking thresholds (Mur-Artal &
// Tardos, T-RO 2017, section III and the TUM settings files: bf = 40, ThDepth = 40). Keys in
// error messages are "tracking.<field>" ("tracking.orb.<field>", "tracking.optimizer.<field>"
// for the embedded structs).

#include "ddl/features/orb_extractor.h"
#include "ddl/optimization/optimizer_config.h"

namespace ddl::tracking {

/// Building a tracking frame from an RGB-D image pair.
struct FrameConfig {
  double bf = 40.0;                     // virtual stereo baseline times fx [m px]: u_r = u - bf / z
  double close_depth_baselines = 40.0;  // "close" points: depth < this * bf / fx (ThDepth)
  double min_depth_m = 0.1;             // depth readings at or below this are ignored [m]
  double max_depth_m = 10.0;            // depth readings above this are ignored [m]
  int depth_edge_radius_px = 2;   // a keypoint within this many pixels of a depth edge gets no
                                  // depth (monocular): its reading may be either side's (0 = off;
                                  // docs/tracking.md, "Keypoints on depth edges")
  double depth_edge_ratio = 0.1;  // a depth edge: a reading in the keypoint's window that differs
                                  // from its own by more than this fraction of its depth
  int bow_levels_up = 3;  // direct index nodes this many levels above the words (depth 2 of the
                          // default 5-level vocabulary, as ORB-SLAM2: 4 of 6)
};

/// Frame-to-frame and frame-to-map matching (ORB-SLAM2 Tracking::TrackWithMotionModel,
/// TrackReferenceKeyFrame, SearchLocalPoints).
struct MatchingConfig {
  float motion_search_radius_px = 15.0f;  // window at level 0 around the motion-model prediction
  int motion_min_matches = 20;            // fewer: retry with twice the window, then give up
  float reference_bow_ratio = 0.7f;  // Lowe ratio for BoW matching against the reference keyframe
  int reference_min_matches = 15;    // fewer BoW matches: reference-keyframe tracking fails
  int min_map_matches = 10;  // inliers with map observations needed after motion/ref tracking
  float local_search_radius = 3.0f;  // window factor of local-map projection search (RGB-D: 3)
  float local_search_radius_after_relocalization = 5.0f;  // the same, 2 frames after a reloc
  float local_search_ratio = 0.8f;    // Lowe ratio (same level) in local-map projection search
  float frustum_min_view_cos = 0.5f;  // points seen at more than 60 deg off their mean view
  int max_local_keyframes = 80;  // neighbours (K2) join the local keyframes while fewer than this;
                                 // those observing the frame's points (K1) all stay (ORB-SLAM2: 80)
  int local_covisibles_per_keyframe = 10;  // best covisibles scanned per local keyframe
  int local_map_min_inliers = 30;          // inliers needed after local-map tracking
  int local_map_min_inliers_after_relocalization = 50;  // ... within max_frames of a reloc
};

/// When to insert a keyframe (ORB-SLAM2 Tracking::NeedNewKeyFrame for RGB-D) and how.
struct KeyFrameConfig {
  int min_frames = 0;   // a keyframe may follow the last one after this many frames if mapping
                        // is idle
  int max_frames = 30;  // ... and is inserted after this many frames at the latest (= fps)
  int frames_after_relocalization = 5;  // no keyframe this many frames after a relocalization
                                        // once the map has more than max_frames keyframes
                                        // (0..max_frames; ORB-SLAM2: max_frames, 30)
  int tracked_close_max = 100;          // "need close points": fewer tracked close points than this
  int non_tracked_close_min = 70;       // ... and more untracked close points than this
  bool close_needs_two_keyframes = true;  // tracked close points count only when seen by >= 2
                                          // keyframes (ORB-SLAM2: false, fresh ones count too)
  float reference_ratio = 0.75f;          // inliers below this fraction of the reference's points
  float reference_ratio_single_keyframe = 0.4f;  // the same while the map has one keyframe
  float weak_tracking_ratio = 0.25f;  // inliers below this fraction: insert even when busy
  int min_inliers = 15;               // never insert with this many inliers or fewer
  int max_queued_keyframes = 3;       // mapping busy: insert only while fewer are queued
  int min_new_close_points = 100;     // new keyframe: create points for at least this many of the
                                      // nearest features, further ones only when close
};

/// Relocalization (ORB-SLAM2 Tracking::Relocalization).
struct RelocalizationConfig {
  bool same_frame = true;               // a frame whose tracking fails tries relocalization at
                                        // once (false: from the next frame on, as ORB-SLAM2)
  float bow_ratio = 0.75f;              // Lowe ratio for BoW matching against each candidate
  int min_bow_matches = 15;             // candidates with fewer BoW matches are skipped
  float min_common_words_ratio = 0.8f;  // candidates share >= this * the best's shared words
  float min_score_ratio = 0.75f;        // candidate groups scoring >= this * the best group's score
  int covisibles_for_score = 10;        // covisibles whose scores add to a candidate's group score
  int pnp_iterations = 300;             // RANSAC iterations of PnP per candidate
  float pnp_reprojection_px = 4.0f;     // RANSAC inlier threshold of PnP [px]
  float pnp_confidence = 0.99f;         // RANSAC confidence
  int pnp_min_inliers = 10;             // PnP / first optimisation must keep this many inliers
  int min_inliers = 50;                 // final inliers for success
  int retry_inliers = 30;               // between this and min_inliers: second, narrower search
  float search_radius_px = 10.0f;       // first projection search window (level 0)
  int search_max_distance = 100;        // ... and its Hamming threshold
  float retry_radius_px = 3.0f;         // second projection search window
  int retry_max_distance = 64;          // ... and its Hamming threshold
};

/// A Gaussian prior on the pose of a frame tracked with the motion model: its constant-velocity
/// prediction joins the motion-only BA of motion-model and local-map tracking as a 6-dof
/// residual (not in ORB-SLAM2). It holds the pose where the features constrain it weakly or
/// pull it off together (motion blur in fast rotation, depth mostly beyond a few metres), which
/// otherwise lets a few frames drift by centimetres (docs/tracking.md, "Motion model and motion
/// prior"). The sigmas hold for one frame interval of the velocity; across a timestamp gap
/// (dropped frames) they grow by E (L + E) / (2 min(L, E)^2), MotionModel::prior.
struct MotionPriorConfig {
  bool enabled = true;                 // add the prior (false: ORB-SLAM2's motion-only BA)
  double sigma_translation_m = 0.005;  // per axis, deviation from the prediction [m]
  double sigma_rotation_deg = 1.0;     // per axis, deviation from the prediction [deg]
};

struct TrackerConfig {
  features::OrbExtractorConfig orb;         // feature extraction (ORB-SLAM2 TUM: 1000, 1.2, 8)
  FrameConfig frame;                        // depth handling, virtual baseline
  MatchingConfig matching;                  // tracking searches
  KeyFrameConfig keyframes;                 // keyframe decision and creation
  RelocalizationConfig relocalization;      // recovery after tracking loss
  MotionPriorConfig motion_prior;           // the motion model's prediction as a pose prior
  optimization::OptimizerConfig optimizer;  // motion-only BA schedule (pose_* fields)
  int init_min_features = 500;              // the first frame needs more keypoints than this
  int init_min_depth_features = 100;        // ... and this many of them with depth (map points)
  int reset_when_lost_max_keyframes = 5;    // lost with <= this many keyframes: reset the map
                                            // (-1: never reset)
  /// Track against a map loaded from a file (`run --load-map`) without adding to it: no keyframe
  /// is created, so local mapping and loop closing have nothing to do (ORB-SLAM2's localization
  /// mode; only the points' match counters count on). Needs a loaded map.
  bool localization_only = false;

  /// Throws ddl::ConfigError naming the key ("tracking.matching.motion_min_matches", ...).
  void validate() const;
};

}  // namespace ddl::tracking
