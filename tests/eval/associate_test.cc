// ddl::io::associate against associate.py's semantics: greedy by smallest |a - (b + offset)|,
// ties broken by a then b, one-to-one, strict max_difference, result sorted by a.

#include "ddl/io/associate.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

namespace ddl::io {
namespace {

using Pairs = std::vector<std::pair<std::size_t, std::size_t>>;

Pairs as_pairs(const std::vector<StampMatch>& m) {
  Pairs out;
  for (const StampMatch& s : m) out.emplace_back(s.first, s.second);
  return out;
}

// A literal transcription of the script's algorithm (all pairs, sort tuples, greedy).
Pairs brute_force(const std::vector<double>& a, const std::vector<double>& b, double offset,
                  double max_difference) {
  std::vector<std::tuple<double, double, double, std::size_t, std::size_t>> cand;
  for (std::size_t i = 0; i < a.size(); ++i) {
    for (std::size_t j = 0; j < b.size(); ++j) {
      const double d = std::abs(a[i] - (b[j] + offset));
      if (d < max_difference) cand.emplace_back(d, a[i], b[j], i, j);
    }
  }
  std::sort(cand.begin(), cand.end());
  std::set<std::size_t> used_a;
  std::set<std::size_t> used_b;
  std::vector<std::tuple<double, double, std::size_t, std::size_t>> matches;
  for (const auto& [d, x, y, i, j] : cand) {
    if (used_a.count(i) || used_b.count(j)) continue;
    used_a.insert(i);
    used_b.insert(j);
    matches.emplace_back(x, y, i, j);
  }
  std::sort(matches.begin(), matches.end());
  Pairs out;
  for (const auto& [x, y, i, j] : matches) out.emplace_back(i, j);
  return out;
}

TEST(AssociateTest, GreedyTakesTheSmallestDifferenceFirst) {
  // 0.01 is closer to 0.008 than 0.0 is, so it wins the only second stamp.
  EXPECT_EQ(as_pairs(associate({0.0, 0.01}, {0.008})), (Pairs{{1, 0}}));
  // Greedy, not a maximum matching: (0.015, 0.01) is taken first and blocks both other pairs.
  EXPECT_EQ(as_pairs(associate({0.0, 0.015}, {0.01, 0.025})), (Pairs{{1, 0}}));
}

TEST(AssociateTest, TiesAreBrokenByFirstThenSecondStamp) {
  EXPECT_EQ(as_pairs(associate({1.0, 3.0}, {2.0}, 0.0, 1.5)), (Pairs{{0, 0}}));
  EXPECT_EQ(as_pairs(associate({2.0}, {3.0, 1.0}, 0.0, 1.5)), (Pairs{{0, 1}}));
}

TEST(AssociateTest, EachStampIsUsedAtMostOnce) {
  EXPECT_EQ(as_pairs(associate({0.0, 0.001, 0.002}, {0.001})), (Pairs{{1, 0}}));
  EXPECT_EQ(as_pairs(associate({0.001}, {0.0, 0.001, 0.002})), (Pairs{{0, 1}}));
}

TEST(AssociateTest, MaxDifferenceIsStrict) {
  EXPECT_TRUE(associate({0.0}, {0.5}, 0.0, 0.5).empty());
  EXPECT_EQ(as_pairs(associate({0.0}, {0.5}, 0.0, 0.500001)), (Pairs{{0, 0}}));
  EXPECT_EQ(as_pairs(associate({0.0}, {0.4375}, 0.0, 0.5)), (Pairs{{0, 0}}));
}

TEST(AssociateTest, OffsetIsAddedToTheSecondList) {
  EXPECT_EQ(as_pairs(associate({10.0}, {0.0}, 10.0)), (Pairs{{0, 0}}));
  EXPECT_EQ(as_pairs(associate({10.0}, {20.0}, -10.0)), (Pairs{{0, 0}}));
  EXPECT_TRUE(associate({10.0}, {20.0}, 10.0).empty());
  EXPECT_TRUE(associate({10.0}, {0.0}).empty());
}

TEST(AssociateTest, ResultIsSortedByFirstStampForUnsortedInput) {
  const auto m = associate({3.0, 1.0, 2.0}, {2.001, 0.999, 3.002});
  EXPECT_EQ(as_pairs(m), (Pairs{{1, 1}, {2, 0}, {0, 2}}));
}

TEST(AssociateTest, MatchesTheScriptOnRandomStampLists) {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> jitter(-0.02, 0.02);
  for (int trial = 0; trial < 20; ++trial) {
    std::vector<double> a;
    std::vector<double> b;
    for (int k = 0; k < 120; ++k) a.push_back(1305031000.0 + k / 30.0 + jitter(rng));
    for (int k = 0; k < 100; ++k) {
      if (rng() % 5 == 0) continue;  // dropped frames
      b.push_back(1305031000.0 + k / 30.0 + 0.5 * jitter(rng));
    }
    std::sort(a.begin(), a.end());
    const double offset = trial % 2 == 0 ? 0.0 : 0.013;
    const double max_difference = trial % 3 == 0 ? 0.02 : 0.01;
    SCOPED_TRACE(trial);
    EXPECT_EQ(as_pairs(associate(a, b, offset, max_difference)),
              brute_force(a, b, offset, max_difference));
  }
}

}  // namespace
}  // namespace ddl::io
