#include "ddl/core/timing.h"

#include <gtest/gtest.h>

namespace ddl {
namespace {

TEST(Timing, MedianMatchesNumpyConvention) {
  EXPECT_DOUBLE_EQ(median({3.0, 1.0, 2.0}), 2.0);
  EXPECT_DOUBLE_EQ(median({4.0, 1.0, 3.0, 2.0}), 2.5);
  EXPECT_DOUBLE_EQ(median({}), 0.0);
}

TEST(Timing, StatsSummarisePerStage) {
  TimingStats stats;
  for (double v : {5.0, 1.0, 3.0}) stats.record("track", v);
  stats.record("segment", 10.0);
  const auto s = stats.summary();
  EXPECT_EQ(s.at("track").count, 3u);
  EXPECT_DOUBLE_EQ(s.at("track").median_ms, 3.0);
  EXPECT_DOUBLE_EQ(s.at("track").max_ms, 5.0);
  EXPECT_DOUBLE_EQ(s.at("segment").mean_ms, 10.0);
}

}  // namespace
}  // namespace ddl
