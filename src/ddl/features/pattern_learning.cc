#include "ddl/features/pattern_learning.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <numeric>

#include "ddl/core/error.h"
#include "ddl/features/matcher.h"

namespace ddl::features {
namespace {

// Bitsets are long here (one bit per training keypoint), so the hardware bit count matters; it
// is chosen at run time as in matcher.cc.
[[gnu::always_inline]] inline std::int64_t count_and_portable(const std::uint64_t* a,
                                                              const std::uint64_t* b, int words) {
  std::int64_t n = 0;
  for (int w = 0; w < words; ++w) n += detail::popcount64(a[w] & b[w]);
  return n;
}

#if defined(__x86_64__) && !defined(__POPCNT__)
[[gnu::target("popcnt")]] std::int64_t count_and_popcnt(const std::uint64_t* a,
                                                        const std::uint64_t* b, int words) {
  std::int64_t n = 0;
  for (int w = 0; w < words; ++w) n += __builtin_popcountll(a[w] & b[w]);
  return n;
}
#endif

std::int64_t count_and(const std::uint64_t* a, const std::uint64_t* b, int words) {
#if defined(__x86_64__) && !defined(__POPCNT__)
  static const bool has_popcnt = __builtin_cpu_supports("popcnt");
  if (has_popcnt) return count_and_popcnt(a, b, words);
#endif
  return count_and_portable(a, b, words);
}

struct TrainingBits {
  int num_candidates = 0;
  int num_keypoints = 0;
  int words = 0;                    // 64-bit words per candidate
  std::vector<std::uint64_t> bits;  // candidate-major: bits[c * words + k / 64] bit k % 64
};

// Evaluates every candidate test on the keypoints of every image. Keypoints are processed in
// blocks of 64: their test results (keypoint-major bytes) are transposed into one word per
// candidate.
TrainingBits evaluate_candidates(const std::vector<cv::Mat>& images, OrbExtractor& extractor,
                                 const std::vector<BriefPair>& candidates, int max_keypoints) {
  const int num_candidates = static_cast<int>(candidates.size());
  const int bytes_per_keypoint = (num_candidates + 7) / 8;
  const int per_image =
      std::max(1, max_keypoints / std::max<int>(1, static_cast<int>(images.size())));

  // Candidate-major storage sized for max_keypoints, compacted at the end.
  const int max_words = (max_keypoints + 63) / 64;
  TrainingBits out;
  out.num_candidates = num_candidates;
  out.bits.assign(static_cast<std::size_t>(num_candidates) * max_words, 0);
  std::vector<std::uint8_t> block(static_cast<std::size_t>(64) * bytes_per_keypoint, 0);
  int in_block = 0;
  int total = 0;
  int word = 0;
  auto flush = [&] {
    if (in_block == 0) return;
    for (int c = 0; c < num_candidates; ++c) {
      std::uint64_t column = 0;
      for (int k = 0; k < in_block; ++k) {
        const std::uint8_t byte =
            block[static_cast<std::size_t>(k) * bytes_per_keypoint + (c >> 3)];
        column |= static_cast<std::uint64_t>((byte >> (c & 7)) & 1u) << k;
      }
      out.bits[static_cast<std::size_t>(c) * max_words + word] = column;
    }
    ++word;
    in_block = 0;
  };

  std::vector<cv::Mat> smoothed;
  for (const cv::Mat& image : images) {
    if (total >= max_keypoints) break;
    const OrbFeatures features = extractor.extract(image);
    const std::vector<cv::Mat>& levels = extractor.pyramid_images();
    smoothed.assign(levels.size(), cv::Mat());
    const int n = static_cast<int>(features.keypoints.size());
    const int take = std::min({n, per_image, max_keypoints - total});
    for (int t = 0; t < take; ++t) {
      // Evenly spread over the image's keypoints (all levels).
      const cv::KeyPoint& kp =
          features.keypoints[static_cast<std::size_t>(static_cast<std::int64_t>(t) * n / take)];
      const cv::Mat& level = levels[kp.octave];
      if (smoothed[kp.octave].empty()) smooth_for_descriptor(level, smoothed[kp.octave]);
      const float sx = static_cast<float>(level.cols) / static_cast<float>(image.cols);
      const float sy = static_cast<float>(level.rows) / static_cast<float>(image.rows);
      const int x = cvRound((kp.pt.x + 0.5f) * sx - 0.5f);
      const int y = cvRound((kp.pt.y + 0.5f) * sy - 0.5f);
      compute_steered_brief(smoothed[kp.octave], x, y, kp.angle, candidates.data(), num_candidates,
                            block.data() + static_cast<std::size_t>(in_block) * bytes_per_keypoint);
      ++total;
      if (++in_block == 64) flush();
    }
  }
  flush();

  out.num_keypoints = total;
  out.words = word;
  for (int c = 0; c < num_candidates; ++c) {  // compact rows to `word` words (front to back)
    std::copy_n(out.bits.begin() + static_cast<std::ptrdiff_t>(c) * max_words, word,
                out.bits.begin() + static_cast<std::ptrdiff_t>(c) * word);
  }
  out.bits.resize(static_cast<std::size_t>(num_candidates) * word);
  out.bits.shrink_to_fit();
  return out;
}

}  // namespace

void PatternLearningOptions::validate() const {
  if (num_candidates < kDescriptorBits || num_candidates > 65536) {
    throw ConfigError::for_key(
        "pattern_learning.num_candidates",
        fmt::format("must be in {}..65536 (got {})", kDescriptorBits, num_candidates));
  }
  if (max_keypoints < kDescriptorBits || max_keypoints > 10'000'000) {
    throw ConfigError::for_key(
        "pattern_learning.max_keypoints",
        fmt::format("must be in {}..10000000 (got {})", kDescriptorBits, max_keypoints));
  }
  if (!(max_bias > 0.0 && max_bias <= 0.5)) {
    throw ConfigError::for_key("pattern_learning.max_bias",
                               fmt::format("must be in (0, 0.5] (got {})", max_bias));
  }
  if (!(initial_max_correlation > 0.0 && initial_max_correlation < 1.0)) {
    throw ConfigError::for_key("pattern_learning.initial_max_correlation",
                               fmt::format("must be in (0, 1) (got {})", initial_max_correlation));
  }
  if (!(correlation_step > 0.0 && correlation_step <= 0.5)) {
    throw ConfigError::for_key("pattern_learning.correlation_step",
                               fmt::format("must be in (0, 0.5] (got {})", correlation_step));
  }
}

PatternLearningResult learn_brief_pattern(const std::vector<cv::Mat>& gray_images,
                                          OrbExtractor& extractor,
                                          const PatternLearningOptions& options) {
  options.validate();
  const std::vector<BriefPair> candidates = make_random_pairs(
      options.seed, options.num_candidates, options.distribution, extractor.config().patch_size);
  const TrainingBits training =
      evaluate_candidates(gray_images, extractor, candidates, options.max_keypoints);
  if (training.num_keypoints < kDescriptorBits) {
    throw InputError(fmt::format(
        "BRIEF pattern learning: the training images gave {} keypoints, at least {} are needed",
        training.num_keypoints, kDescriptorBits));
  }
  const double n = training.num_keypoints;
  const int words = training.words;
  auto column = [&](int c) { return training.bits.data() + static_cast<std::size_t>(c) * words; };

  std::vector<double> mean(candidates.size());
  for (int c = 0; c < training.num_candidates; ++c) {
    mean[c] = static_cast<double>(count_and(column(c), column(c), words)) / n;
  }
  // 1. Order by distance of the mean from 0.5 (ties: candidate order). Constant tests carry no
  //    information and are never chosen.
  std::vector<int> order;
  for (int c = 0; c < training.num_candidates; ++c) {
    if (mean[c] > 0.0 && mean[c] < 1.0 && std::fabs(mean[c] - 0.5) <= options.max_bias) {
      order.push_back(c);
    }
  }
  std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
    return std::fabs(mean[a] - 0.5) < std::fabs(mean[b] - 0.5);
  });
  auto abs_correlation = [&](int a, int b) {
    const double p11 = static_cast<double>(count_and(column(a), column(b), words)) / n;
    const double cov = p11 - mean[a] * mean[b];
    return std::fabs(cov) / std::sqrt(mean[a] * (1.0 - mean[a]) * mean[b] * (1.0 - mean[b]));
  };

  // 2. Greedy search with a rising correlation threshold.
  PatternLearningResult result;
  std::vector<int> selected;
  for (double threshold = options.initial_max_correlation; threshold < 1.0 + 1e-12;
       threshold += options.correlation_step) {
    selected.clear();
    for (int c : order) {
      bool ok = true;
      for (int s : selected) {
        if (abs_correlation(c, s) > threshold) {
          ok = false;
          break;
        }
      }
      if (!ok) continue;
      selected.push_back(c);
      if (static_cast<int>(selected.size()) == kDescriptorBits) break;
    }
    if (static_cast<int>(selected.size()) == kDescriptorBits) {
      result.max_correlation = threshold;
      break;
    }
  }
  if (static_cast<int>(selected.size()) < kDescriptorBits) {
    throw InputError(
        fmt::format("BRIEF pattern learning: only {} informative candidate tests among {}, need {}",
                    selected.size(), candidates.size(), kDescriptorBits));
  }

  result.num_keypoints = training.num_keypoints;
  double bias_selected = 0.0;
  double bias_first = 0.0;
  for (int k = 0; k < kDescriptorBits; ++k) {
    result.pattern[k] = candidates[selected[k]];
    bias_selected += std::fabs(mean[selected[k]] - 0.5);
    bias_first += std::fabs(mean[k] - 0.5);
  }
  result.selected_mean_abs_bias = bias_selected / kDescriptorBits;
  result.first_256_mean_abs_bias = bias_first / kDescriptorBits;
  return result;
}

DescriptorBitStatistics descriptor_bit_statistics(const cv::Mat& descriptors) {
  DescriptorBitStatistics stats;
  const int n = descriptors.rows;
  if (n == 0) return stats;
  std::vector<double> ones(kDescriptorBits, 0.0);
  std::vector<double> both(static_cast<std::size_t>(kDescriptorBits) * kDescriptorBits, 0.0);
  std::vector<int> set_bits;
  for (int r = 0; r < n; ++r) {
    const std::uint8_t* d = descriptors.ptr<std::uint8_t>(r);
    set_bits.clear();
    for (int b = 0; b < kDescriptorBits; ++b) {
      if ((d[b >> 3] >> (b & 7)) & 1) set_bits.push_back(b);
    }
    for (int a : set_bits) {
      ones[a] += 1.0;
      for (int b : set_bits) both[static_cast<std::size_t>(a) * kDescriptorBits + b] += 1.0;
    }
  }
  double bias = 0.0;
  for (double& p : ones) {
    p /= n;
    bias += std::fabs(p - 0.5);
  }
  double correlation = 0.0;
  int pairs = 0;
  for (int a = 0; a < kDescriptorBits; ++a) {
    for (int b = a + 1; b < kDescriptorBits; ++b) {
      const double var = ones[a] * (1 - ones[a]) * ones[b] * (1 - ones[b]);
      if (var <= 0.0) continue;
      const double p11 = both[static_cast<std::size_t>(a) * kDescriptorBits + b] / n;
      correlation += std::fabs(p11 - ones[a] * ones[b]) / std::sqrt(var);
      ++pairs;
    }
  }
  stats.mean_abs_bias = bias / kDescriptorBits;
  stats.mean_abs_correlation = pairs > 0 ? correlation / pairs : 0.0;
  return stats;
}

std::string format_pattern_table(const BriefPattern& pattern) {
  std::string out;
  for (const BriefPair& p : pattern) {
    out += fmt::format("{{{}, {}, {}, {}}},\n", p.x1, p.y1, p.x2, p.y2);
  }
  return out;
}

}  // namespace ddl::features
