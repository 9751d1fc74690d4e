#include "ddl/mapping/local_mapper_config.h"

#include <fmt/format.h>

#include <cmath>
#include <string>

#include "ddl/core/error.h"

namespace ddl::mapping {
namespace {

void require(bool ok, const std::string& key, const std::string& what) {
  if (!ok) throw ConfigError::for_key(key, what);
}

void require_positive(double value, const std::string& key) {
  require(std::isfinite(value) && value > 0.0, key,
          fmt::format("must be a positive number (got {})", value));
}

void require_ratio(double value, const std::string& key) {
  require(std::isfinite(value) && value >= 0.0 && value <= 1.0, key,
          fmt::format("must be in [0, 1] (got {})", value));
}

void require_int(int value, int lo, int hi, const std::string& key) {
  require(value >= lo && value <= hi, key,
          fmt::format("must be in {}..{} (got {})", lo, hi, value));
}

}  // namespace

void LocalMapperConfig::validate() const {
  require_positive(bf, "mapping.bf");
  require_positive(close_depth_baselines, "mapping.close_depth_baselines");
  require_int(bow_levels_up, 0, 10, "mapping.bow_levels_up");

  const std::string t = "mapping.triangulation.";
  require_int(triangulation.neighbours, 1, 1000, t + "neighbours");
  require_int(triangulation.max_hamming, 0, 256, t + "max_hamming");
  require_positive(triangulation.epipolar_chi2, t + "epipolar_chi2");
  require(std::isfinite(triangulation.epipole_min_px) && triangulation.epipole_min_px >= 0.0,
          t + "epipole_min_px", fmt::format("must be >= 0 (got {})", triangulation.epipole_min_px));
  require(std::isfinite(triangulation.max_parallax_cos) && triangulation.max_parallax_cos > 0.0 &&
              triangulation.max_parallax_cos <= 1.0,
          t + "max_parallax_cos",
          fmt::format("must be in (0, 1] (got {})", triangulation.max_parallax_cos));
  require_positive(triangulation.chi2_mono, t + "chi2_mono");
  require_positive(triangulation.chi2_stereo, t + "chi2_stereo");
  require(std::isfinite(triangulation.scale_consistency) && triangulation.scale_consistency >= 1.0,
          t + "scale_consistency",
          fmt::format("must be >= 1 (got {})", triangulation.scale_consistency));

  const std::string f = "mapping.fusion.";
  require_int(fusion.neighbours, 0, 1000, f + "neighbours");
  require_int(fusion.second_neighbours, 0, 1000, f + "second_neighbours");
  require_positive(fusion.radius_factor, f + "radius_factor");
  require_int(fusion.max_hamming, 0, 256, f + "max_hamming");
  require_positive(fusion.chi2_mono, f + "chi2_mono");
  require_positive(fusion.chi2_stereo, f + "chi2_stereo");
  require(std::isfinite(fusion.min_view_cos) && fusion.min_view_cos >= -1.0 &&
              fusion.min_view_cos <= 1.0,
          f + "min_view_cos", fmt::format("must be in [-1, 1] (got {})", fusion.min_view_cos));

  const std::string p = "mapping.point_culling.";
  require_ratio(point_culling.min_found_ratio, p + "min_found_ratio");
  require_int(point_culling.max_observations, 0, 1000, p + "max_observations");
  require_int(point_culling.observation_window, 1, 1000, p + "observation_window");
  require(point_culling.probation_keyframes > point_culling.observation_window,
          p + "probation_keyframes",
          fmt::format("must exceed mapping.point_culling.observation_window ({}) (got {})",
                      point_culling.observation_window, point_culling.probation_keyframes));

  const std::string k = "mapping.keyframe_culling.";
  require_ratio(keyframe_culling.redundant_ratio, k + "redundant_ratio");
  require_int(keyframe_culling.min_other_observers, 1, 1000, k + "min_other_observers");

  require_int(local_ba_min_keyframes, 2, 1000000, "mapping.local_ba_min_keyframes");
  require_int(local_ba_max_keyframes, 0, 1000000, "mapping.local_ba_max_keyframes");
  try {
    optimizer.validate();
  } catch (const ConfigError& e) {
    // OptimizerConfig names its keys "optimizer.<field>"; here they live under "mapping.".
    throw e.with_key_prefix("mapping.");
  }
}

}  // namespace ddl::mapping
