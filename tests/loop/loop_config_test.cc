#include <gtest/gtest.h>

#include "config_error_check.h"
#include "ddl/core/error.h"
#include "ddl/loop/loop_closer_config.h"

namespace ddl::loop {
namespace {

::testing::AssertionResult rejects(const LoopCloserConfig& config, const std::string& key) {
  return test_support::throws_config_error_for_key([&] { config.validate(); }, key);
}

TEST(LoopCloserConfig, DefaultsAreValid) { EXPECT_NO_THROW(LoopCloserConfig{}.validate()); }

TEST(LoopCloserConfig, BadValuesNameTheirKey) {
  LoopCloserConfig c;
  c.bf = -1.0;
  EXPECT_TRUE(rejects(c, "loop.bf"));
  c = {};
  c.detection.consistency_threshold = -1;
  EXPECT_TRUE(rejects(c, "loop.detection.consistency_threshold"));
  c = {};
  c.verification.ransac_probability = 1.0;
  EXPECT_TRUE(rejects(c, "loop.verification.ransac_probability"));
  c = {};
  c.verification.min_loop_matches = 0;
  EXPECT_TRUE(rejects(c, "loop.verification.min_loop_matches"));
  c = {};
  c.correction.essential_graph_min_weight = 0;
  EXPECT_TRUE(rejects(c, "loop.correction.essential_graph_min_weight"));
  c = {};
  c.optimizer.pose_graph_iterations = 0;
  EXPECT_TRUE(rejects(c, "loop.optimizer.pose_graph_iterations"));
}

}  // namespace
}  // namespace ddl::loop
