#include "ddl/features/brief_pattern.h"

#include <gtest/gtest.h>

#include <cmath>
#include <set>
#include <tuple>

#include "config_error_check.h"
#include "ddl/core/error.h"
#include "ddl/features/orb_extractor.h"
#include "ddl/features/pattern_learning.h"
#include "features_test_support.h"

namespace ddl::features {
namespace {

using PairKey = std::tuple<int, int, int, int>;

PairKey canonical(const BriefPair& p) {
  return std::min(PairKey{p.x1, p.y1, p.x2, p.y2}, PairKey{p.x2, p.y2, p.x1, p.y1});
}

void expect_valid_pairs(const std::vector<BriefPair>& pairs, int radius) {
  std::set<PairKey> seen;
  for (const BriefPair& p : pairs) {
    EXPECT_LE(p.x1 * p.x1 + p.y1 * p.y1, radius * radius);
    EXPECT_LE(p.x2 * p.x2 + p.y2 * p.y2, radius * radius);
    EXPECT_FALSE(p.x1 == p.x2 && p.y1 == p.y2) << "degenerate test";
    EXPECT_TRUE(seen.insert(canonical(p)).second) << "repeated test";
  }
}

TEST(BriefPattern, GeneratorIsDeterministicAndPrefixStable) {
  for (PairDistribution d : {PairDistribution::kGaussian, PairDistribution::kUniformDisc}) {
    const auto a = make_random_pairs(kDefaultBriefPatternSeed, 300, d);
    const auto b = make_random_pairs(kDefaultBriefPatternSeed, 1000, d);
    const auto c = make_random_pairs(kDefaultBriefPatternSeed + 1, 300, d);
    ASSERT_EQ(a.size(), 300u);
    EXPECT_TRUE(std::equal(a.begin(), a.end(), b.begin()));
    EXPECT_NE(a, c);
  }
}

TEST(BriefPattern, PairsStayInsideThePatchAndAreDistinct) {
  expect_valid_pairs(make_random_pairs(7, 4096, PairDistribution::kGaussian), 15);
  expect_valid_pairs(make_random_pairs(7, 4096, PairDistribution::kUniformDisc), 15);
  expect_valid_pairs(make_random_pairs(7, 512, PairDistribution::kGaussian, 15), 7);
}

TEST(BriefPattern, CoordinateSpreadMatchesTheDistribution) {
  auto spread = [](const std::vector<BriefPair>& pairs) {
    double sum = 0.0;
    double sum2 = 0.0;
    for (const BriefPair& p : pairs) {
      for (int v : {p.x1, p.y1, p.x2, p.y2}) {
        sum += v;
        sum2 += v * v;
      }
    }
    const double n = 4.0 * pairs.size();
    return std::pair{sum / n, std::sqrt(sum2 / n - (sum / n) * (sum / n))};
  };
  // G II: sigma = 31 / 5 = 6.2, slightly less after clipping to the radius-15 disc.
  const auto [g_mean, g_std] = spread(make_random_pairs(3, 8192, PairDistribution::kGaussian));
  EXPECT_NEAR(g_mean, 0.0, 0.15);
  EXPECT_GT(g_std, 5.7);
  EXPECT_LT(g_std, 6.4);
  // G I: uniform on a disc of radius 15 has E[x^2] = r^2 / 4, std 7.5.
  const auto [u_mean, u_std] = spread(make_random_pairs(3, 8192, PairDistribution::kUniformDisc));
  EXPECT_NEAR(u_mean, 0.0, 0.15);
  EXPECT_NEAR(u_std, 7.5, 0.3);
}

TEST(BriefPattern, DefaultPatternWasSelectedFromOurGenerator) {
  const BriefPattern& pattern = default_brief_pattern();
  expect_valid_pairs(std::vector<BriefPair>(pattern.begin(), pattern.end()), 15);
  EXPECT_LE(pattern_radius(pattern), 15.0);
  // Provenance: every test of the compiled-in table is one of the generator's candidates.
  std::set<PairKey> pool;
  for (const BriefPair& p :
       make_random_pairs(kDefaultBriefPatternSeed, PatternLearningOptions{}.num_candidates,
                         PairDistribution::kUniformDisc)) {
    pool.insert(PairKey{p.x1, p.y1, p.x2, p.y2});
  }
  for (const BriefPair& p : pattern) {
    EXPECT_TRUE(pool.count(PairKey{p.x1, p.y1, p.x2, p.y2}))
        << "test {" << int(p.x1) << ", " << int(p.y1) << ", " << int(p.x2) << ", " << int(p.y2)
        << "} is not a generator candidate";
  }
}

TEST(PatternLearning, SelectsLessBiasedTestsThanRawCandidates) {
  std::vector<cv::Mat> images;
  for (std::uint64_t seed = 11; seed < 15; ++seed) {
    images.push_back(test::make_textured_image({480, 360}, seed));
  }
  OrbExtractor extractor{OrbExtractorConfig{}};
  PatternLearningOptions options;
  options.num_candidates = 2048;
  options.max_keypoints = 2048;
  options.max_bias = 0.1;
  const PatternLearningResult a = learn_brief_pattern(images, extractor, options);
  EXPECT_GE(a.num_keypoints, 1500);
  EXPECT_LT(a.selected_mean_abs_bias, 0.1);
  EXPECT_LT(a.selected_mean_abs_bias, 0.5 * a.first_256_mean_abs_bias);
  EXPECT_GE(a.max_correlation, options.initial_max_correlation);
  // All selected tests come from the candidate pool, and the search is deterministic.
  const auto pool = make_random_pairs(options.seed, options.num_candidates, options.distribution);
  for (const BriefPair& p : a.pattern) {
    EXPECT_NE(std::find(pool.begin(), pool.end(), p), pool.end());
  }
  const PatternLearningResult b = learn_brief_pattern(images, extractor, options);
  EXPECT_EQ(a.pattern, b.pattern);

  // Descriptors made with the learned pattern are less biased than with raw Gaussian tests.
  const cv::Mat held_out = test::make_textured_image({640, 480}, 99);
  OrbExtractor raw{OrbExtractorConfig{}, make_gaussian_pattern()};
  OrbExtractor learned{OrbExtractorConfig{}, a.pattern};
  const auto raw_stats = descriptor_bit_statistics(raw.extract(held_out).descriptors);
  const auto learned_stats = descriptor_bit_statistics(learned.extract(held_out).descriptors);
  EXPECT_LT(learned_stats.mean_abs_bias, raw_stats.mean_abs_bias);
}

TEST(PatternLearning, OptionsNameTheBadKey) {
  auto rejects = [](auto mutate, const std::string& key) {
    PatternLearningOptions o;
    mutate(o);
    return test_support::throws_config_error_for_key([&] { o.validate(); }, key);
  };
  EXPECT_TRUE(rejects([](auto& o) { o.num_candidates = 10; }, "pattern_learning.num_candidates"));
  EXPECT_TRUE(rejects([](auto& o) { o.max_bias = 0.0; }, "pattern_learning.max_bias"));
  EXPECT_TRUE(
      rejects([](auto& o) { o.correlation_step = -1; }, "pattern_learning.correlation_step"));
}

TEST(PatternLearning, TooFewKeypointsIsAnInputError) {
  OrbExtractor extractor{OrbExtractorConfig{}};
  const std::vector<cv::Mat> flat{cv::Mat(200, 200, CV_8UC1, cv::Scalar(90))};
  EXPECT_THROW(learn_brief_pattern(flat, extractor), InputError);
}

}  // namespace
}  // namespace ddl::features
