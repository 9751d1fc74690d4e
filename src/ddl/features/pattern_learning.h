#pragma once
// Learning the 256 tests of the steered BRIEF pattern (ORB, Rublee et al., ICCV 2011, section
// 4.3): once steered by the keypoint orientation, random tests become biased (their mean moves
// away from 0.5) and correlated, which shrinks the distance between unrelated descriptors. The
// greedy search keeps, from a pool of candidate tests, those closest to a 0.5 mean whose
// correlation with every test kept before stays under a threshold, raised until 256 are found.
// Unlike ORB, candidates whose bias exceeds max_bias are excluded up front: without the cap the
// search, forced deep into the list by the correlation limit, picked tests with a mean bias of
// 0.17 (on TUM frames; 0.04 with the cap), and unrelated descriptors came out 105 bits apart on
// average instead of 126.
// Used offline by bench/learn_brief_pattern.cc to write brief_pattern_table.inc; tests run it on
// synthetic images.

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "ddl/features/brief_pattern.h"
#include "ddl/features/orb_extractor.h"

namespace ddl::features {

struct PatternLearningOptions {
  int num_candidates = 32768;  // random pairs the 256 tests are chosen from
  PairDistribution distribution = PairDistribution::kUniformDisc;  // of the candidate pairs
  std::uint64_t seed = kDefaultBriefPatternSeed;                   // seed of make_random_pairs()
  int max_keypoints = 32768;             // training keypoints used, spread evenly over the images
  double max_bias = 0.05;                // candidates with |mean - 0.5| above this are never used
  double initial_max_correlation = 0.2;  // first threshold on |Pearson correlation| of two tests
  double correlation_step = 0.02;        // threshold increase when fewer than 256 tests pass

  /// Throws ddl::ConfigError naming the key ("pattern_learning.num_candidates", ...).
  void validate() const;
};

struct PatternLearningResult {
  BriefPattern pattern;
  int num_keypoints = 0;                 // training keypoints used
  double max_correlation = 0.0;          // threshold at which 256 tests were found
  double selected_mean_abs_bias = 0.0;   // mean |mean - 0.5| of the selected tests (training set)
  double first_256_mean_abs_bias = 0.0;  // the same for the first 256 (unselected) candidates
};

/// Runs `extractor` on every grayscale image, evaluates all candidate tests on (up to
/// max_keypoints of) the oriented keypoints found, and returns the greedy selection. Deterministic.
/// Throws ddl::InputError when the images give fewer than 256 keypoints.
PatternLearningResult learn_brief_pattern(const std::vector<cv::Mat>& gray_images,
                                          OrbExtractor& extractor,
                                          const PatternLearningOptions& options = {});

/// Bit statistics of a set of descriptors (rows of an N x 32 CV_8U matrix): mean over bits of
/// |fraction of ones - 0.5|, and mean over bit pairs of |Pearson correlation|.
struct DescriptorBitStatistics {
  double mean_abs_bias = 0.0;
  double mean_abs_correlation = 0.0;
};
DescriptorBitStatistics descriptor_bit_statistics(const cv::Mat& descriptors);

/// The pattern as the initializer lines of brief_pattern_table.inc ("{x1, y1, x2, y2},").
std::string format_pattern_table(const BriefPattern& pattern);

}  // namespace ddl::features
