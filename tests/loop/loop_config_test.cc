#include <gtest/gtest.h>

#include "ddl/core/error.h"
#include "ddl/loop/loop_closer_config.h"

namespace ddl::loop {
namespace {

void expect_key_error(const LoopCloserConfig& config, const std::string& key) {
  try {
    config.validate();
    FAIL() << "expected a ConfigError for " << key;
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("'" + key + "'"), std::string::npos) << e.what();
  }
}

TEST(LoopCloserConfig, DefaultsAreValid) { EXPECT_NO_THROW(LoopCloserConfig{}.validate()); }

TEST(LoopCloserConfig, BadValuesNameTheirKey) {
  LoopCloserConfig c;
  c.bf = -1.0;
  expect_key_error(c, "loop.bf");
  c = {};
  c.detection.consistency_threshold = -1;
  expect_key_error(c, "loop.detection.consistency_threshold");
  c = {};
  c.verification.ransac_probability = 1.0;
  expect_key_error(c, "loop.verification.ransac_probability");
  c = {};
  c.verification.min_loop_matches = 0;
  expect_key_error(c, "loop.verification.min_loop_matches");
  c = {};
  c.correction.essential_graph_min_weight = 0;
  expect_key_error(c, "loop.correction.essential_graph_min_weight");
  c = {};
  c.optimizer.pose_graph_iterations = 0;
  expect_key_error(c, "loop.optimizer.pose_graph_iterations");
}

}  // namespace
}  // namespace ddl::loop
