#include "ddl/tracking/tracker_config.h"

#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "config_error_check.h"
#include "ddl/core/error.h"

namespace ddl::tracking {
namespace {

::testing::AssertionResult rejects(const TrackerConfig& config, const std::string& key) {
  return test_support::throws_config_error_for_key([&] { config.validate(); }, key);
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
  EXPECT_TRUE(rejects(c, "tracking.matching.local_search_ratio"));
  c = TrackerConfig{};
  c.frame.max_depth_m = 0.05;
  EXPECT_TRUE(rejects(c, "tracking.frame.max_depth_m"));
  c = TrackerConfig{};
  c.keyframes.max_frames = -1;
  EXPECT_TRUE(rejects(c, "tracking.keyframes.max_frames"));
  c = TrackerConfig{};
  c.keyframes.frames_after_relocalization = -1;
  EXPECT_TRUE(rejects(c, "tracking.keyframes.frames_after_relocalization"));
  c.keyframes.frames_after_relocalization = c.keyframes.max_frames + 1;
  EXPECT_TRUE(rejects(c, "tracking.keyframes.frames_after_relocalization"));
  c.keyframes.frames_after_relocalization = c.keyframes.max_frames;  // ORB-SLAM2's hold
  EXPECT_NO_THROW(c.validate());
  c = TrackerConfig{};
  c.relocalization.retry_inliers = 60;
  EXPECT_TRUE(rejects(c, "tracking.relocalization.retry_inliers"));
  c = TrackerConfig{};
  c.orb.num_levels = 0;
  EXPECT_TRUE(rejects(c, "tracking.orb.num_levels"));
  c = TrackerConfig{};
  c.optimizer.pose_rounds = 0;
  EXPECT_TRUE(rejects(c, "tracking.optimizer.pose_rounds"));
  c = TrackerConfig{};
  c.motion_prior.sigma_translation_m = 0.0;
  EXPECT_TRUE(rejects(c, "tracking.motion_prior.sigma_translation_m"));
  c = TrackerConfig{};
  c.motion_prior.sigma_rotation_deg = std::nan("");
  EXPECT_TRUE(rejects(c, "tracking.motion_prior.sigma_rotation_deg"));
  c = TrackerConfig{};
  c.frame.depth_edge_radius_px = -1;
  EXPECT_TRUE(rejects(c, "tracking.frame.depth_edge_radius_px"));
  c.frame.depth_edge_radius_px = 33;
  EXPECT_TRUE(rejects(c, "tracking.frame.depth_edge_radius_px"));
  c = TrackerConfig{};
  c.frame.depth_edge_ratio = 0.0;
  EXPECT_TRUE(rejects(c, "tracking.frame.depth_edge_ratio"));
  c.frame.depth_edge_ratio = std::nan("");
  EXPECT_TRUE(rejects(c, "tracking.frame.depth_edge_ratio"));
}

}  // namespace
}  // namespace ddl::tracking
