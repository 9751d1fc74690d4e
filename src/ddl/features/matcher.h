#pragma once
// Descriptor matching utilities: Hamming distance of 256-bit ORB descriptors, brute-force matching
// with Lowe's ratio test and a mutual check, and ORB-SLAM2's rotation-consistency histogram.
// All functions are pure (thread-safe); RotationHistogram instances are not shared.

#include <array>
#include <cstdint>
#include <cstring>
#include <limits>
#include <opencv2/core.hpp>
#include <vector>

#include "ddl/features/brief_pattern.h"

namespace ddl::features {

/// Strict Hamming distance threshold of ORB-SLAM2's matchers (TH_LOW), in bits.
inline constexpr int kThLow = 50;
/// Loose Hamming distance threshold of ORB-SLAM2's matchers (TH_HIGH), in bits.
inline constexpr int kThHigh = 100;
/// Bins of the rotation-consistency histogram (ORB-SLAM2's HISTO_LENGTH).
inline constexpr int kRotationHistogramBins = 30;

namespace detail {
inline int popcount64(std::uint64_t x) {
#if defined(__POPCNT__)
  return __builtin_popcountll(x);
#else
  // Without -mpopcnt (the portable x86-64 baseline) __builtin_popcountll becomes a call into
  // libgcc; this branch-free bit count (Hacker's Delight 5-1) inlines and is several times faster.
  x = x - ((x >> 1) & 0x5555555555555555ULL);
  x = (x & 0x3333333333333333ULL) + ((x >> 2) & 0x3333333333333333ULL);
  x = (x + (x >> 4)) & 0x0F0F0F0F0F0F0F0FULL;
  return static_cast<int>((x * 0x0101010101010101ULL) >> 56);
#endif
}
}  // namespace detail

/// Hamming distance (number of differing bits, 0..256) between two 32-byte descriptors.
inline int hamming_distance(const std::uint8_t* a, const std::uint8_t* b) {
  int distance = 0;
  for (int k = 0; k < kDescriptorBytes; k += 8) {
    std::uint64_t wa;
    std::uint64_t wb;
    std::memcpy(&wa, a + k, 8);
    std::memcpy(&wb, b + k, 8);
    distance += detail::popcount64(wa ^ wb);
  }
  return distance;
}

/// Hamming distance between row `row_a` of `a` and row `row_b` of `b` (N x 32 CV_8U matrices).
inline int hamming_distance(const cv::Mat& a, int row_a, const cv::Mat& b, int row_b) {
  return hamming_distance(a.ptr<std::uint8_t>(row_a), b.ptr<std::uint8_t>(row_b));
}

/// The nearest and the second-nearest candidate offered so far, for Lowe's ratio test (ORB-SLAM2's
/// matchers keep both). Strict comparisons: of equal distances the first offered stays nearest.
struct NearestTwo {
  static constexpr int kNone = std::numeric_limits<int>::max();  // nothing offered yet
  int best = kNone;                                              // Hamming distances in bits
  int second = kNone;
  int best_index = -1;
  int best_level = -1;  // pyramid levels of the two, where a matcher compares them
  int second_level = -1;

  bool found() const { return best_index >= 0; }
  void offer(int distance, int index, int level = -1) {
    if (distance < best) {
      second = best;
      second_level = best_level;
      best = distance;
      best_index = index;
      best_level = level;
    } else if (distance < second) {
      second = distance;
      second_level = level;
    }
  }
};

struct BruteForceMatchOptions {
  int max_distance = kThHigh;  // matches with a larger Hamming distance are rejected
  float ratio = 0.8f;          // keep if best < ratio * second best (Lowe); 1 disables the test
  bool mutual = true;          // keep only pairs that are each other's nearest neighbour

  /// Throws ddl::ConfigError naming the key ("match.max_distance", ...).
  void validate() const;
};

/// Matches every row of `query` to its nearest row of `train` (both N x 32 CV_8U descriptor
/// matrices). A match is kept when its distance is <= max_distance, passes the ratio test against
/// the second-nearest train row, and (if mutual) the query row is also the nearest of the train
/// row. Ties go to the lower index. Output: one DMatch per kept query row (queryIdx, trainIdx,
/// distance in bits), in query order. Throws ddl::InputError on matrices of the wrong type.
std::vector<cv::DMatch> match_brute_force(const cv::Mat& query, const cv::Mat& train,
                                          const BruteForceMatchOptions& options = {});

/// Rotation-consistency check of ORB-SLAM2 (Mur-Artal & Tardos 2017): between two images all
/// correct matches rotate by about the same angle, so the orientation change of each match is put
/// into a histogram of `num_bins` bins (bin k centred on k * 360 / num_bins degrees) and only
/// matches in the three most populated bins survive; the second and third bins only count when
/// they hold at least 10% of the largest one.
class RotationHistogram {
 public:
  explicit RotationHistogram(int num_bins = kRotationHistogramBins);

  /// Records match `id` whose keypoint orientation goes from `angle_from_deg` to `angle_to_deg`.
  void add(float angle_from_deg, float angle_to_deg, int id);
  /// Bin of an orientation change, 0..num_bins-1.
  int bin_of(float angle_from_deg, float angle_to_deg) const;
  /// The up to three kept bins, largest first; -1 where there is none.
  std::array<int, 3> top_bins() const;
  /// Ids added whose bin is not kept (the matches to discard), in insertion order.
  std::vector<int> inconsistent_ids() const;
  /// Ids added whose bin is kept, in insertion order.
  std::vector<int> consistent_ids() const;
  void clear();

 private:
  int num_bins_;
  std::vector<int> counts_;
  std::vector<std::pair<int, int>> entries_;  // (bin, id)
};

/// Convenience: the matches of `matches` (queryIdx into `query_keypoints`, trainIdx into
/// `train_keypoints`) that pass the rotation-consistency check, in their original order.
std::vector<cv::DMatch> filter_by_rotation(const std::vector<cv::DMatch>& matches,
                                           const std::vector<cv::KeyPoint>& query_keypoints,
                                           const std::vector<cv::KeyPoint>& train_keypoints,
                                           int num_bins = kRotationHistogramBins);

}  // namespace ddl::features
