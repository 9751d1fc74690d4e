#include "ddl/features/matcher.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>

#include "config_error_check.h"
#include "ddl/core/error.h"

namespace ddl::features {
namespace {

cv::Mat random_descriptors(int rows, std::uint32_t seed) {
  std::mt19937 rng(seed);
  cv::Mat d(rows, kDescriptorBytes, CV_8UC1);
  for (int r = 0; r < rows; ++r) {
    for (int c = 0; c < kDescriptorBytes; ++c) d.at<std::uint8_t>(r, c) = rng() & 0xFF;
  }
  return d;
}

int naive_distance(const std::uint8_t* a, const std::uint8_t* b) {
  int n = 0;
  for (int bit = 0; bit < kDescriptorBits; ++bit) {
    n += ((a[bit / 8] >> (bit % 8)) & 1) != ((b[bit / 8] >> (bit % 8)) & 1);
  }
  return n;
}

// Flips `bits` distinct bits of row `row` of `d`.
void flip_bits(cv::Mat& d, int row, int bits, std::mt19937& rng) {
  std::vector<int> positions(kDescriptorBits);
  std::iota(positions.begin(), positions.end(), 0);
  std::shuffle(positions.begin(), positions.end(), rng);
  for (int k = 0; k < bits; ++k) {
    d.at<std::uint8_t>(row, positions[k] / 8) ^=
        static_cast<std::uint8_t>(1u << (positions[k] % 8));
  }
}

TEST(Matcher, ThresholdsAreOrbSlam2s) {
  EXPECT_EQ(kThLow, 50);
  EXPECT_EQ(kThHigh, 100);
  EXPECT_EQ(kRotationHistogramBins, 30);
}

TEST(Matcher, HammingDistanceEqualsNaiveBitCount) {
  const cv::Mat a = random_descriptors(300, 1);
  const cv::Mat b = random_descriptors(300, 2);
  for (int r = 0; r < 300; ++r) {
    EXPECT_EQ(hamming_distance(a, r, b, r),
              naive_distance(a.ptr<std::uint8_t>(r), b.ptr<std::uint8_t>(r)));
  }
  EXPECT_EQ(hamming_distance(a, 7, a, 7), 0);
  cv::Mat inverted;
  cv::bitwise_not(a, inverted);
  EXPECT_EQ(hamming_distance(a, 3, inverted, 3), 256);
  std::mt19937_64 rng(3);
  for (int k = 0; k < 1000; ++k) {
    const std::uint64_t x = rng();
    EXPECT_EQ(detail::popcount64(x), __builtin_popcountll(x));
  }
  EXPECT_EQ(detail::popcount64(0), 0);
  EXPECT_EQ(detail::popcount64(~0ULL), 64);
}

TEST(Matcher, BruteForceFindsPerturbedCopies) {
  const cv::Mat train = random_descriptors(400, 4);
  std::mt19937 rng(5);
  std::vector<int> order(train.rows);
  std::iota(order.begin(), order.end(), 0);
  std::shuffle(order.begin(), order.end(), rng);
  cv::Mat query(train.rows, kDescriptorBytes, CV_8UC1);
  std::vector<int> flipped(train.rows);
  for (int q = 0; q < train.rows; ++q) {
    train.row(order[q]).copyTo(query.row(q));
    flipped[q] = static_cast<int>(rng() % 20);
    flip_bits(query, q, flipped[q], rng);
  }
  const auto matches = match_brute_force(query, train);
  ASSERT_EQ(matches.size(), static_cast<std::size_t>(train.rows));
  for (const cv::DMatch& m : matches) {
    EXPECT_EQ(m.trainIdx, order[m.queryIdx]);
    EXPECT_EQ(m.distance, static_cast<float>(flipped[m.queryIdx]));
  }
}

TEST(Matcher, RatioTestRejectsAmbiguousMatches) {
  // The query is 20 bits from train 0 and 22 bits from train 1: 20 < 0.8 * 22 fails.
  std::mt19937 rng(6);
  cv::Mat train = random_descriptors(2, 7);
  const cv::Mat query = train.row(0).clone();
  train.row(0).copyTo(train.row(1));
  flip_bits(train, 0, 20, rng);
  flip_bits(train, 1, 22, rng);
  BruteForceMatchOptions options;
  options.mutual = false;
  EXPECT_TRUE(match_brute_force(query, train, options).empty());
  options.ratio = 1.0f;
  const auto matches = match_brute_force(query, train, options);
  ASSERT_EQ(matches.size(), 1u);
  EXPECT_EQ(matches[0].trainIdx, 0);
}

TEST(Matcher, MutualCheckKeepsOnlyTheClosestQuery) {
  std::mt19937 rng(8);
  cv::Mat train = random_descriptors(2, 9);
  cv::Mat query(2, kDescriptorBytes, CV_8UC1);
  train.row(0).copyTo(query.row(0));
  train.row(0).copyTo(query.row(1));
  flip_bits(query, 0, 5, rng);
  flip_bits(query, 1, 9, rng);
  BruteForceMatchOptions options;
  options.mutual = false;
  EXPECT_EQ(match_brute_force(query, train, options).size(), 2u);
  options.mutual = true;
  const auto matches = match_brute_force(query, train, options);
  ASSERT_EQ(matches.size(), 1u);
  EXPECT_EQ(matches[0].queryIdx, 0);
}

TEST(Matcher, MaxDistanceIsInclusive) {
  std::mt19937 rng(10);
  cv::Mat train = random_descriptors(1, 11);
  cv::Mat query = train.clone();
  flip_bits(query, 0, kThLow, rng);
  BruteForceMatchOptions options;
  options.max_distance = kThLow;
  EXPECT_EQ(match_brute_force(query, train, options).size(), 1u);
  options.max_distance = kThLow - 1;
  EXPECT_TRUE(match_brute_force(query, train, options).empty());
}

TEST(Matcher, BadInputsAreReported) {
  BruteForceMatchOptions options;
  options.ratio = 1.5f;
  EXPECT_TRUE(
      test_support::throws_config_error_for_key([&] { options.validate(); }, "match.ratio"));
  options = {};
  options.max_distance = 300;
  EXPECT_THROW(options.validate(), ConfigError);
  EXPECT_THROW(match_brute_force(cv::Mat(3, 16, CV_8UC1), random_descriptors(3, 1)), InputError);
  EXPECT_TRUE(match_brute_force(cv::Mat(), random_descriptors(3, 1)).empty());
}

TEST(RotationHistogram, KeepsTheDominantRotationAndDropsOutliers) {
  RotationHistogram histogram;
  std::mt19937 rng(12);
  std::uniform_real_distribution<float> noise(-4.0f, 4.0f);
  std::uniform_real_distribution<float> any(0.0f, 360.0f);
  for (int id = 0; id < 200; ++id) {
    const float from = any(rng);
    histogram.add(from, from + 30.0f + noise(rng), id);  // inliers: +30 deg
  }
  std::vector<int> outliers;
  for (int id = 200; id < 230; ++id) {
    const float from = any(rng);
    const float rotation = 90.0f + 6.0f * (id - 200);  // spread over 90..264 deg
    histogram.add(from, from + rotation, id);
    outliers.push_back(id);
  }
  const auto bad = histogram.inconsistent_ids();
  EXPECT_EQ(bad, outliers);
  const auto good = histogram.consistent_ids();
  EXPECT_EQ(good.size(), 200u);
  // 30 +- 4 deg at 12 deg per bin straddles bins 2 and 3 (centred on 24 and 36 deg).
  const auto top = histogram.top_bins();
  EXPECT_EQ(std::min(top[0], top[1]), 2);
  EXPECT_EQ(std::max(top[0], top[1]), 3);
}

TEST(RotationHistogram, WrapsAroundAndIgnoresSmallPeaks) {
  RotationHistogram histogram(30);
  EXPECT_EQ(histogram.bin_of(10.0f, 8.0f), 0);   // -2 deg
  EXPECT_EQ(histogram.bin_of(350.0f, 2.0f), 1);  // +12 deg
  EXPECT_EQ(histogram.bin_of(0.0f, 359.0f), 0);  // -1 deg
  EXPECT_EQ(histogram.bin_of(0.0f, 180.0f), 15);
  for (int id = 0; id < 100; ++id) histogram.add(0.0f, 0.0f, id);
  for (int id = 100; id < 109; ++id) histogram.add(0.0f, 120.0f, id);  // 9% of the main peak
  const auto top = histogram.top_bins();
  EXPECT_EQ(top[0], 0);
  EXPECT_EQ(top[1], -1);
  EXPECT_EQ(histogram.inconsistent_ids().size(), 9u);
  histogram.add(0.0f, 120.0f, 109);  // now 10%: kept as the second peak
  EXPECT_EQ(histogram.top_bins()[1], 10);
  EXPECT_TRUE(histogram.inconsistent_ids().empty());
  histogram.clear();
  EXPECT_TRUE(histogram.consistent_ids().empty());
  EXPECT_EQ(histogram.top_bins()[0], -1);
}

// A bad bin count is a configuration error, also when negative (it was std::length_error from
// sizing the counts first; review, stop 26).
TEST(RotationHistogram, ABadBinCountNamesTheKey) {
  for (const int bins : {0, -1}) {
    EXPECT_TRUE(test_support::throws_config_error_for_key([&] { RotationHistogram h(bins); },
                                                          "match.rotation_bins"))
        << bins;
  }
}

TEST(RotationHistogram, FilterByRotationUsesKeypointAngles) {
  std::vector<cv::KeyPoint> a(4);
  std::vector<cv::KeyPoint> b(4);
  const float angles_a[] = {10, 100, 200, 300};
  const float angles_b[] = {40, 131, 230, 150};  // +30, +31, +30, and -150 deg
  for (int i = 0; i < 4; ++i) {
    a[i].angle = angles_a[i];
    b[i].angle = angles_b[i];
  }
  std::vector<cv::DMatch> matches;
  for (int i = 0; i < 4; ++i) matches.emplace_back(i, i, 0.0f);
  for (int k = 0; k < 20; ++k) matches.emplace_back(0, 0, 1.0f);  // make the +30 peak dominant
  const auto kept = filter_by_rotation(matches, a, b);
  EXPECT_EQ(kept.size(), 23u);
  for (const cv::DMatch& m : kept) EXPECT_NE(m.queryIdx, 3);
}

}  // namespace
}  // namespace ddl::features
