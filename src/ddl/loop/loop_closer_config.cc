#include "ddl/loop/loop_closer_config.h"

#include <fmt/format.h>

#include <cmath>
#include <string>

#include "ddl/core/error.h"

namespace ddl::loop {
namespace {

void require(bool ok, const std::string& key, const std::string& what) {
  if (!ok) throw ConfigError::for_key(key, what);
}

void require_positive(double value, const std::string& key) {
  require(std::isfinite(value) && value > 0.0, key,
          fmt::format("must be a positive number (got {})", value));
}

void require_ratio(double value, const std::string& key) {
  require(std::isfinite(value) && value > 0.0 && value <= 1.0, key,
          fmt::format("must be in (0, 1] (got {})", value));
}

void require_int(int value, int lo, int hi, const std::string& key) {
  require(value >= lo && value <= hi, key,
          fmt::format("must be in {}..{} (got {})", lo, hi, value));
}

}  // namespace

void LoopCloserConfig::validate() const {
  require_positive(bf, "loop.bf");

  const std::string d = "loop.detection.";
  require_int(detection.min_keyframes_between_loops, 0, 1000000, d + "min_keyframes_between_loops");
  require_ratio(detection.min_common_words_ratio, d + "min_common_words_ratio");
  require_int(detection.score_covisibles, 0, 1000, d + "score_covisibles");
  require_ratio(detection.min_group_score_ratio, d + "min_group_score_ratio");
  require_int(detection.consistency_threshold, 0, 100, d + "consistency_threshold");
  require_int(detection.covisible_confirmations, 0, 100, d + "covisible_confirmations");

  const std::string v = "loop.verification.";
  require_ratio(verification.bow_ratio, v + "bow_ratio");
  require_int(verification.max_hamming, 0, 256, v + "max_hamming");
  require_int(verification.min_bow_matches, 3, 100000, v + "min_bow_matches");
  require_int(verification.ransac_max_iterations, 1, 1000000, v + "ransac_max_iterations");
  require(std::isfinite(verification.ransac_probability) && verification.ransac_probability > 0.0 &&
              verification.ransac_probability < 1.0,
          v + "ransac_probability",
          fmt::format("must be in (0, 1) (got {})", verification.ransac_probability));
  require_int(verification.ransac_min_inliers, 3, 100000, v + "ransac_min_inliers");
  require_positive(verification.ransac_chi2, v + "ransac_chi2");
  require_positive(verification.candidate_search_radius, v + "candidate_search_radius");
  require_int(verification.min_refined_inliers, 3, 100000, v + "min_refined_inliers");
  require_positive(verification.loop_search_radius, v + "loop_search_radius");
  require_int(verification.min_loop_matches, 3, 100000, v + "min_loop_matches");
  require_int(verification.min_confirmation_inliers, 3, 100000, v + "min_confirmation_inliers");

  const std::string c = "loop.correction.";
  require_positive(correction.fuse_radius, c + "fuse_radius");
  require_int(correction.fuse_max_hamming, 0, 256, c + "fuse_max_hamming");
  require_int(correction.essential_graph_min_weight, 1, 100000, c + "essential_graph_min_weight");

  try {
    optimizer.validate();
  } catch (const ConfigError& e) {
    // OptimizerConfig names its keys "optimizer.<field>"; here they live under "loop.".
    throw e.with_key_prefix("loop.");
  }
}

}  // namespace ddl::loop
