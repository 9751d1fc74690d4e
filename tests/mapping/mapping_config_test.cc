#include <gtest/gtest.h>

#include "ddl/core/error.h"
#include "ddl/mapping/local_mapper_config.h"

namespace ddl::mapping {
namespace {

void expect_key_error(const LocalMapperConfig& config, const std::string& key) {
  try {
    config.validate();
    FAIL() << "expected a ConfigError for " << key;
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("'" + key + "'"), std::string::npos) << e.what();
  }
}

TEST(LocalMapperConfig, DefaultsAreValid) { EXPECT_NO_THROW(LocalMapperConfig{}.validate()); }

TEST(LocalMapperConfig, BadValuesNameTheirKey) {
  LocalMapperConfig c;
  c.bf = 0.0;
  expect_key_error(c, "mapping.bf");
  c = {};
  c.triangulation.neighbours = 0;
  expect_key_error(c, "mapping.triangulation.neighbours");
  c = {};
  c.fusion.max_hamming = 300;
  expect_key_error(c, "mapping.fusion.max_hamming");
  c = {};
  c.point_culling.probation_keyframes = 2;
  expect_key_error(c, "mapping.point_culling.probation_keyframes");
  c = {};
  c.keyframe_culling.redundant_ratio = 1.5;
  expect_key_error(c, "mapping.keyframe_culling.redundant_ratio");
  c = {};
  c.optimizer.num_threads = 0;
  expect_key_error(c, "mapping.optimizer.num_threads");
}

}  // namespace
}  // namespace ddl::mapping
