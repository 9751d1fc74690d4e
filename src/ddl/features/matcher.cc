#include "ddl/features/matcher.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <limits>

#include "ddl/core/error.h"

namespace ddl::features {
namespace {

template <bool kHardwarePopcount>
[[gnu::always_inline]] inline int distance_32(const std::uint8_t* a, const std::uint8_t* b) {
  if constexpr (kHardwarePopcount) {
    int d = 0;
    for (int k = 0; k < kDescriptorBytes; k += 8) {
      std::uint64_t wa;
      std::uint64_t wb;
      std::memcpy(&wa, a + k, 8);
      std::memcpy(&wb, b + k, 8);
      d += __builtin_popcountll(wa ^ wb);
    }
    return d;
  } else {
    return hamming_distance(a, b);
  }
}

// One pass over all pairs: the two nearest train rows of every query row, and the nearest query
// row of every train row (for the mutual check). Strict comparisons: ties keep the lower index.
template <bool kHardwarePopcount>
[[gnu::always_inline]] inline void scan_all_pairs(const cv::Mat& query, const cv::Mat& train,
                                                  NearestTwo* per_query, int* train_best,
                                                  int* train_best_query) {
  for (int i = 0; i < query.rows; ++i) {
    const std::uint8_t* q = query.ptr<std::uint8_t>(i);
    NearestTwo n;
    for (int j = 0; j < train.rows; ++j) {
      const int d = distance_32<kHardwarePopcount>(q, train.ptr<std::uint8_t>(j));
      n.offer(d, j);
      if (d < train_best[j]) {
        train_best[j] = d;
        train_best_query[j] = i;
      }
    }
    per_query[i] = n;
  }
}

#if defined(__x86_64__) && !defined(__POPCNT__)
// Compiled for CPUs with the POPCNT instruction and chosen at run time, so the portable build
// still gets the hardware bit count in its hottest loop.
[[gnu::target("popcnt")]] void scan_all_pairs_popcnt(const cv::Mat& query, const cv::Mat& train,
                                                     NearestTwo* per_query, int* train_best,
                                                     int* train_best_query) {
  scan_all_pairs<true>(query, train, per_query, train_best, train_best_query);
}
#endif

void scan(const cv::Mat& query, const cv::Mat& train, NearestTwo* per_query, int* train_best,
          int* train_best_query) {
#if defined(__x86_64__) && !defined(__POPCNT__)
  if (__builtin_cpu_supports("popcnt")) {
    scan_all_pairs_popcnt(query, train, per_query, train_best, train_best_query);
    return;
  }
  scan_all_pairs<false>(query, train, per_query, train_best, train_best_query);
#elif defined(__POPCNT__)
  scan_all_pairs<true>(query, train, per_query, train_best, train_best_query);
#else
  scan_all_pairs<false>(query, train, per_query, train_best, train_best_query);
#endif
}

void check_descriptors(const cv::Mat& m, const char* name) {
  if (!m.empty() && (m.type() != CV_8UC1 || m.cols != kDescriptorBytes)) {
    throw InputError(fmt::format(
        "brute-force matcher: {} descriptors must be N x {} CV_8U, got {} x {} of type {}", name,
        kDescriptorBytes, m.rows, m.cols, m.type()));
  }
}

}  // namespace

void BruteForceMatchOptions::validate() const {
  if (max_distance < 0 || max_distance > kDescriptorBits) {
    throw ConfigError::for_key("match.max_distance", fmt::format("must be in 0..{} (got {})",
                                                                 kDescriptorBits, max_distance));
  }
  if (!(ratio > 0.0f && ratio <= 1.0f)) {
    throw ConfigError::for_key("match.ratio", fmt::format("must be in (0, 1] (got {})", ratio));
  }
}

std::vector<cv::DMatch> match_brute_force(const cv::Mat& query, const cv::Mat& train,
                                          const BruteForceMatchOptions& options) {
  options.validate();
  check_descriptors(query, "query");
  check_descriptors(train, "train");
  std::vector<cv::DMatch> matches;
  if (query.empty() || train.empty()) return matches;

  std::vector<NearestTwo> per_query(query.rows);
  std::vector<int> train_best(train.rows, std::numeric_limits<int>::max());
  std::vector<int> train_best_query(train.rows, -1);
  scan(query, train, per_query.data(), train_best.data(), train_best_query.data());

  for (int i = 0; i < query.rows; ++i) {
    const NearestTwo& n = per_query[i];
    if (n.best_index < 0 || n.best > options.max_distance) continue;
    if (options.ratio < 1.0f && n.second != NearestTwo::kNone &&
        !(static_cast<float>(n.best) < options.ratio * static_cast<float>(n.second))) {
      continue;
    }
    if (options.mutual && train_best_query[n.best_index] != i) continue;
    matches.emplace_back(i, n.best_index, static_cast<float>(n.best));
  }
  return matches;
}

RotationHistogram::RotationHistogram(int num_bins) : num_bins_(num_bins) {
  // Checked before sizing: a negative count would be a huge size_t (std::length_error).
  if (num_bins < 1) {
    throw ConfigError::for_key("match.rotation_bins",
                               fmt::format("must be at least 1 (got {})", num_bins));
  }
  counts_.assign(static_cast<std::size_t>(num_bins), 0);
}

int RotationHistogram::bin_of(float angle_from_deg, float angle_to_deg) const {
  double rotation = std::fmod(static_cast<double>(angle_to_deg) - angle_from_deg, 360.0);
  if (rotation < 0.0) rotation += 360.0;
  const int bin = static_cast<int>(std::lround(rotation * num_bins_ / 360.0));
  return bin >= num_bins_ ? bin - num_bins_ : bin;
}

void RotationHistogram::add(float angle_from_deg, float angle_to_deg, int id) {
  const int bin = bin_of(angle_from_deg, angle_to_deg);
  ++counts_[bin];
  entries_.emplace_back(bin, id);
}

std::array<int, 3> RotationHistogram::top_bins() const {
  std::array<int, 3> top{-1, -1, -1};
  std::array<int, 3> top_count{0, 0, 0};
  for (int bin = 0; bin < num_bins_; ++bin) {
    const int c = counts_[bin];
    if (c > top_count[0]) {
      top = {bin, top[0], top[1]};
      top_count = {c, top_count[0], top_count[1]};
    } else if (c > top_count[1]) {
      top = {top[0], bin, top[1]};
      top_count = {top_count[0], c, top_count[1]};
    } else if (c > top_count[2]) {
      top[2] = bin;
      top_count[2] = c;
    }
  }
  // Minor peaks only count if they are not negligible next to the main one (ORB-SLAM2: 10%).
  for (int k = 1; k < 3; ++k) {
    if (top[k] >= 0 && top_count[k] < 0.1 * top_count[0]) top[k] = -1;
  }
  if (top[1] < 0) top[2] = -1;
  return top;
}

std::vector<int> RotationHistogram::inconsistent_ids() const {
  const std::array<int, 3> top = top_bins();
  std::vector<int> ids;
  for (const auto& [bin, id] : entries_) {
    if (bin != top[0] && bin != top[1] && bin != top[2]) ids.push_back(id);
  }
  return ids;
}

std::vector<int> RotationHistogram::consistent_ids() const {
  const std::array<int, 3> top = top_bins();
  std::vector<int> ids;
  for (const auto& [bin, id] : entries_) {
    if (bin == top[0] || bin == top[1] || bin == top[2]) ids.push_back(id);
  }
  return ids;
}

void RotationHistogram::clear() {
  std::fill(counts_.begin(), counts_.end(), 0);
  entries_.clear();
}

std::vector<cv::DMatch> filter_by_rotation(const std::vector<cv::DMatch>& matches,
                                           const std::vector<cv::KeyPoint>& query_keypoints,
                                           const std::vector<cv::KeyPoint>& train_keypoints,
                                           int num_bins) {
  RotationHistogram histogram(num_bins);
  for (std::size_t k = 0; k < matches.size(); ++k) {
    const cv::DMatch& m = matches[k];
    histogram.add(query_keypoints.at(m.queryIdx).angle, train_keypoints.at(m.trainIdx).angle,
                  static_cast<int>(k));
  }
  std::vector<cv::DMatch> kept;
  for (int k : histogram.consistent_ids()) kept.push_back(matches[k]);
  return kept;
}

}  // namespace ddl::features
