#include "ddl/tracking/tracker_config.h"

#include <gtest/gtest.h>

#include <string>

#include "ddl/core/error.h"

namespace ddl::tracking {
namespace {

std::string error_of(const TrackerConfig& config) {
  try {
    config.validate();
  } catch (const ConfigError& e) {
    return e.what();
  }
  return "";
}

TEST(TrackerConfigTest, DefaultsAreValidAndFollowOrbSlam2) {
  const TrackerConfig config;
  EXPECT_NO_THROW(config.validate());
  EXPECT_EQ(config.frame.bf, 40.0);
  EXPECT_EQ(config.frame.close_depth_baselines, 40.0);
  EXPECT_EQ(config.matching.max_local_keyframes, 80);
  EXPECT_EQ(config.orb.num_features, 1000);
}

TEST(TrackerConfigTest, ErrorsNameTheKey) {
  TrackerConfig c;
  c.matching.local_search_ratio = 1.5f;
  EXPECT_NE(error_of(c).find("tracking.matching.local_search_ratio"), std::string::npos);
  c = TrackerConfig{};
  c.frame.max_depth_m = 0.05;
  EXPECT_NE(error_of(c).find("tracking.frame.max_depth_m"), std::string::npos);
  c = TrackerConfig{};
  c.keyframes.max_frames = -1;
  EXPECT_NE(error_of(c).find("tracking.keyframes.max_frames"), std::string::npos);
  c = TrackerConfig{};
  c.relocalization.retry_inliers = 60;
  EXPECT_NE(error_of(c).find("tracking.relocalization.retry_inliers"), std::string::npos);
  c = TrackerConfig{};
  c.orb.num_levels = 0;
  EXPECT_NE(error_of(c).find("tracking.orb.num_levels"), std::string::npos) << error_of(c);
  c = TrackerConfig{};
  c.optimizer.pose_rounds = 0;
  EXPECT_NE(error_of(c).find("tracking.optimizer.pose_rounds"), std::string::npos) << error_of(c);
}

}  // namespace
}  // namespace ddl::tracking
