#include "ddl/vocabulary/bow_vector.h"

#include <gtest/gtest.h>

#include <string>

#include "config_error_check.h"
#include "ddl/core/error.h"
#include "ddl/vocabulary/vocabulary_config.h"

namespace ddl::vocabulary {
namespace {

TEST(BowVector, FromEntriesSortsMergesAndDropsNonPositive) {
  const BowVector v =
      BowVector::from_entries({{7, 0.5}, {2, 1.0}, {7, 0.25}, {4, 0.0}, {9, -1.0}, {3, 2.0}});
  ASSERT_EQ(v.size(), 3u);
  EXPECT_EQ(v.entries()[0], (BowEntry{2, 1.0}));
  EXPECT_EQ(v.entries()[1], (BowEntry{3, 2.0}));
  EXPECT_EQ(v.entries()[2], (BowEntry{7, 0.75}));
  EXPECT_EQ(v.weight(7), 0.75);
  EXPECT_EQ(v.weight(4), 0.0);
  EXPECT_EQ(v.weight(100), 0.0);
  EXPECT_DOUBLE_EQ(v.l1_norm(), 3.75);
}

TEST(BowVector, NormalizeL1MakesWeightsSumToOne) {
  BowVector v = BowVector::from_entries({{1, 3.0}, {5, 1.0}});
  v.normalize_l1();
  EXPECT_DOUBLE_EQ(v.weight(1), 0.75);
  EXPECT_DOUBLE_EQ(v.weight(5), 0.25);
  BowVector empty;
  empty.normalize_l1();
  EXPECT_TRUE(empty.empty());
}

TEST(L1Score, MatchesTheDefinitionOnHandComputedCases) {
  const BowVector a = BowVector::from_entries({{1, 0.5}, {2, 0.5}});
  const BowVector b = BowVector::from_entries({{2, 0.5}, {3, 0.5}});
  // |a - b|_1 = 0.5 + 0 + 0.5 = 1  ->  s = 1 - 0.5 = 0.5
  EXPECT_DOUBLE_EQ(l1_score(a, b), 0.5);
  EXPECT_DOUBLE_EQ(l1_score(b, a), 0.5);
  // Scale does not matter: the score normalises both vectors.
  const BowVector a_scaled = BowVector::from_entries({{1, 4.0}, {2, 4.0}});
  EXPECT_DOUBLE_EQ(l1_score(a_scaled, b), 0.5);
  const BowVector c = BowVector::from_entries({{1, 0.7}, {2, 0.3}});
  const BowVector d = BowVector::from_entries({{1, 0.4}, {2, 0.6}});
  EXPECT_NEAR(l1_score(c, d), 0.7, 1e-12);  // 1 - 0.5 * (0.3 + 0.3)
  EXPECT_EQ(l1_score(a, a), 1.0);
  EXPECT_EQ(l1_score(a, BowVector::from_entries({{8, 1.0}})), 0.0);
  EXPECT_EQ(l1_score(a, BowVector{}), 0.0);
}

TEST(FeatureVector, GroupsFeaturesByNodeSorted) {
  const FeatureVector fv = FeatureVector::from_pairs({{12, 4}, {3, 9}, {12, 1}, {3, 2}, {40, 0}});
  ASSERT_EQ(fv.size(), 3u);
  EXPECT_EQ(fv.nodes()[0].node_id, 3u);
  EXPECT_EQ(fv.nodes()[0].feature_indices, (std::vector<std::uint32_t>{2, 9}));
  EXPECT_EQ(fv.nodes()[1].node_id, 12u);
  EXPECT_EQ(fv.nodes()[1].feature_indices, (std::vector<std::uint32_t>{1, 4}));
  ASSERT_NE(fv.find(40), nullptr);
  EXPECT_EQ(*fv.find(40), (std::vector<std::uint32_t>{0}));
  EXPECT_EQ(fv.find(5), nullptr);
  EXPECT_EQ(fv.feature_count(), 5u);
}

::testing::AssertionResult rejects(const VocabularyConfig& config, const std::string& key) {
  return test_support::throws_config_error_for_key([&] { config.validate(); }, key);
}

TEST(VocabularyConfig, ValidateNamesTheBadKey) {
  EXPECT_NO_THROW(VocabularyConfig{}.validate());
  VocabularyConfig c;
  c.branching = 1;
  EXPECT_TRUE(rejects(c, "branching"));
  c = {};
  c.branching = 65;
  EXPECT_TRUE(rejects(c, "branching"));
  c = {};
  c.levels = 0;
  EXPECT_TRUE(rejects(c, "levels"));
  c = {};
  c.levels = 11;
  EXPECT_TRUE(rejects(c, "levels"));
  c = {};
  c.max_iterations = 0;
  EXPECT_TRUE(rejects(c, "max_iterations"));
  c = {};
  c.threads = 0;
  EXPECT_TRUE(rejects(c, "threads"));
  c = {};
  c.weighting = static_cast<Weighting>(9);
  EXPECT_TRUE(rejects(c, "weighting"));
}

TEST(VocabularyConfig, WeightingNamesRoundTrip) {
  for (Weighting w : {Weighting::kTfIdf, Weighting::kTf, Weighting::kIdf, Weighting::kBinary}) {
    EXPECT_EQ(parse_weighting(to_string(w)), w);
  }
  EXPECT_FALSE(parse_weighting("tfidf").has_value());
}

}  // namespace
}  // namespace ddl::vocabulary
