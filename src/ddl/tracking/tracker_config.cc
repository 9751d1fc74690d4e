#include "ddl/tracking/tracker_config.h"

#include <fmt/format.h>

#include <cmath>
#include <string>

#include "ddl/core/error.h"

namespace ddl::tracking {
namespace {

template <typename T>
void require(bool ok, const std::string& key, T value, const char* what) {
  if (!ok) throw ConfigError::for_key(key, fmt::format("{} (got {})", what, value));
}

void require_positive(double value, const std::string& key) {
  require(std::isfinite(value) && value > 0.0, key, value, "must be a positive number");
}

void require_ratio(double value, const std::string& key) {
  require(std::isfinite(value) && value > 0.0 && value <= 1.0, key, value, "must be in (0, 1]");
}

void require_count(int value, int lo, int hi, const std::string& key) {
  require(value >= lo && value <= hi, key, value, fmt::format("must be in {}..{}", lo, hi).c_str());
}

void validate_frame(const FrameConfig& c) {
  const std::string p = "tracking.frame.";
  require_positive(c.bf, p + "bf");
  require_positive(c.close_depth_baselines, p + "close_depth_baselines");
  require(std::isfinite(c.min_depth_m) && c.min_depth_m >= 0.0, p + "min_depth_m", c.min_depth_m,
          "must be >= 0");
  require(std::isfinite(c.max_depth_m) && c.max_depth_m > c.min_depth_m, p + "max_depth_m",
          c.max_depth_m, "must be greater than tracking.frame.min_depth_m");
  require_count(c.depth_edge_radius_px, 0, 32, p + "depth_edge_radius_px");
  require(std::isfinite(c.depth_edge_ratio) && c.depth_edge_ratio > 0.0, p + "depth_edge_ratio",
          c.depth_edge_ratio, "must be > 0");
  require_count(c.bow_levels_up, 0, 10, p + "bow_levels_up");
}

void validate_matching(const MatchingConfig& c) {
  const std::string p = "tracking.matching.";
  require_positive(c.motion_search_radius_px, p + "motion_search_radius_px");
  require_count(c.motion_min_matches, 1, 100000, p + "motion_min_matches");
  require_ratio(c.reference_bow_ratio, p + "reference_bow_ratio");
  require_count(c.reference_min_matches, 1, 100000, p + "reference_min_matches");
  require_count(c.min_map_matches, 1, 100000, p + "min_map_matches");
  require_positive(c.local_search_radius, p + "local_search_radius");
  require_positive(c.local_search_radius_after_relocalization,
                   p + "local_search_radius_after_relocalization");
  require_ratio(c.local_search_ratio, p + "local_search_ratio");
  require(std::isfinite(c.frustum_min_view_cos) && c.frustum_min_view_cos >= -1.0f &&
              c.frustum_min_view_cos <= 1.0f,
          p + "frustum_min_view_cos", c.frustum_min_view_cos, "must be in [-1, 1]");
  require_count(c.max_local_keyframes, 1, 100000, p + "max_local_keyframes");
  require_count(c.local_covisibles_per_keyframe, 0, 100000, p + "local_covisibles_per_keyframe");
  require_count(c.local_map_min_inliers, 1, 100000, p + "local_map_min_inliers");
  require_count(c.local_map_min_inliers_after_relocalization, 1, 100000,
                p + "local_map_min_inliers_after_relocalization");
}

void validate_keyframes(const KeyFrameConfig& c) {
  const std::string p = "tracking.keyframes.";
  require_count(c.min_frames, 0, 100000, p + "min_frames");
  require(c.max_frames >= c.min_frames && c.max_frames <= 100000, p + "max_frames", c.max_frames,
          "must be in tracking.keyframes.min_frames..100000");
  // At most max_frames: the tracker starts as if relocalized at frame 0, and a longer hold would
  // keep a fresh map of more than max_frames keyframes from growing.
  require(c.frames_after_relocalization >= 0 && c.frames_after_relocalization <= c.max_frames,
          p + "frames_after_relocalization", c.frames_after_relocalization,
          "must be in 0..tracking.keyframes.max_frames");
  require_count(c.tracked_close_max, 0, 100000, p + "tracked_close_max");
  require_count(c.non_tracked_close_min, 0, 100000, p + "non_tracked_close_min");
  require_ratio(c.reference_ratio, p + "reference_ratio");
  require_ratio(c.reference_ratio_single_keyframe, p + "reference_ratio_single_keyframe");
  require_ratio(c.weak_tracking_ratio, p + "weak_tracking_ratio");
  require_count(c.min_inliers, 0, 100000, p + "min_inliers");
  require_count(c.max_queued_keyframes, 1, 100000, p + "max_queued_keyframes");
  require_count(c.min_new_close_points, 0, 100000, p + "min_new_close_points");
}

void validate_relocalization(const RelocalizationConfig& c) {
  const std::string p = "tracking.relocalization.";
  require_ratio(c.bow_ratio, p + "bow_ratio");
  require_count(c.min_bow_matches, 4, 100000, p + "min_bow_matches");
  require_ratio(c.min_common_words_ratio, p + "min_common_words_ratio");
  require_ratio(c.min_score_ratio, p + "min_score_ratio");
  require_count(c.covisibles_for_score, 0, 100000, p + "covisibles_for_score");
  require_count(c.pnp_iterations, 1, 100000, p + "pnp_iterations");
  require_positive(c.pnp_reprojection_px, p + "pnp_reprojection_px");
  require(std::isfinite(c.pnp_confidence) && c.pnp_confidence > 0.0f && c.pnp_confidence < 1.0f,
          p + "pnp_confidence", c.pnp_confidence, "must be in (0, 1)");
  require_count(c.pnp_min_inliers, 4, 100000, p + "pnp_min_inliers");
  require_count(c.min_inliers, 4, 100000, p + "min_inliers");
  require(c.retry_inliers >= 0 && c.retry_inliers <= c.min_inliers, p + "retry_inliers",
          c.retry_inliers, "must be in 0..tracking.relocalization.min_inliers");
  require_positive(c.search_radius_px, p + "search_radius_px");
  require_count(c.search_max_distance, 0, 256, p + "search_max_distance");
  require_positive(c.retry_radius_px, p + "retry_radius_px");
  require_count(c.retry_max_distance, 0, 256, p + "retry_max_distance");
}

void validate_motion_prior(const MotionPriorConfig& c) {
  const std::string p = "tracking.motion_prior.";
  require_positive(c.sigma_translation_m, p + "sigma_translation_m");
  require_positive(c.sigma_rotation_deg, p + "sigma_rotation_deg");
}

}  // namespace

void TrackerConfig::validate() const {
  // The embedded structs name their keys "orb.<field>" / "optimizer.<field>"; here they live
  // under "tracking.".
  auto nested = [](const auto& config) {
    try {
      config.validate();
    } catch (const ConfigError& e) {
      throw e.with_key_prefix("tracking.");
    }
  };
  nested(orb);
  nested(optimizer);
  validate_frame(frame);
  validate_matching(matching);
  validate_keyframes(keyframes);
  validate_relocalization(relocalization);
  validate_motion_prior(motion_prior);
  require_count(init_min_features, 0, 1000000, "tracking.init_min_features");
  require_count(init_min_depth_features, 0, 1000000, "tracking.init_min_depth_features");
  require(reset_when_lost_max_keyframes >= -1, "tracking.reset_when_lost_max_keyframes",
          reset_when_lost_max_keyframes, "must be >= -1");
}

}  // namespace ddl::tracking
