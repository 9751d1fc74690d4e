#include <gtest/gtest.h>

#include "config_error_check.h"
#include "ddl/core/error.h"
#include "ddl/mapping/local_mapper_config.h"

namespace ddl::mapping {
namespace {

::testing::AssertionResult rejects(const LocalMapperConfig& config, const std::string& key) {
  return test_support::throws_config_error_for_key([&] { config.validate(); }, key);
}

TEST(LocalMapperConfig, DefaultsAreValid) { EXPECT_NO_THROW(LocalMapperConfig{}.validate()); }

TEST(LocalMapperConfig, BadValuesNameTheirKey) {
  LocalMapperConfig c;
  c.bf = 0.0;
  EXPECT_TRUE(rejects(c, "mapping.bf"));
  c = {};
  c.triangulation.neighbours = 0;
  EXPECT_TRUE(rejects(c, "mapping.triangulation.neighbours"));
  c = {};
  c.fusion.max_hamming = 300;
  EXPECT_TRUE(rejects(c, "mapping.fusion.max_hamming"));
  c = {};
  c.point_culling.probation_keyframes = 2;
  EXPECT_TRUE(rejects(c, "mapping.point_culling.probation_keyframes"));
  c = {};
  c.keyframe_culling.redundant_ratio = 1.5;
  EXPECT_TRUE(rejects(c, "mapping.keyframe_culling.redundant_ratio"));
  c = {};
  c.optimizer.num_threads = 0;
  EXPECT_TRUE(rejects(c, "mapping.optimizer.num_threads"));
}

}  // namespace
}  // namespace ddl::mapping
