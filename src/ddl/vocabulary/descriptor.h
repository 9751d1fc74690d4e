#pragma once
// 256-bit binary descriptors (ORB rBRIEF) as four 64-bit words, and their Hamming distance.
// A cv::Mat of descriptors is N x 32 CV_8U, one descriptor per row; byte b of a row holds bits
// 8b..8b+7 of the descriptor, so a row and its Descriptor share the same memory layout.

#include <array>
#include <cstdint>
#include <cstring>
#include <opencv2/core.hpp>
#include <vector>

namespace ddl::vocabulary {

inline constexpr int kDescriptorBytes = 32;  // 256 bits
inline constexpr int kDescriptorBits = 256;

/// One 256-bit descriptor. Word w holds bytes 8w..8w+7 of the cv::Mat row (little-endian).
using Descriptor = std::array<std::uint64_t, 4>;

/// Hamming distance (number of differing bits), 0..256.
inline int hamming_distance(const Descriptor& a, const Descriptor& b) {
  return __builtin_popcountll(a[0] ^ b[0]) + __builtin_popcountll(a[1] ^ b[1]) +
         __builtin_popcountll(a[2] ^ b[2]) + __builtin_popcountll(a[3] ^ b[3]);
}

/// The descriptor stored in 32 bytes at `bytes` (e.g. mat.ptr<uint8_t>(row)).
inline Descriptor descriptor_from_bytes(const std::uint8_t* bytes) {
  Descriptor d;
  std::memcpy(d.data(), bytes, kDescriptorBytes);
  return d;
}

/// Copies a descriptor into 32 bytes at `bytes`.
inline void descriptor_to_bytes(const Descriptor& d, std::uint8_t* bytes) {
  std::memcpy(bytes, d.data(), kDescriptorBytes);
}

// Batch kernels used by training and by descriptor-to-word lookup. On x86-64 builds without
// -mpopcnt they are compiled twice (hardware POPCNT and generic) and picked at run time, so a
// portable binary still uses the POPCNT instruction; results are identical either way.

/// Index of the candidate nearest to `d` (the first one on ties); its distance in *distance.
/// `count` must be >= 1.
int nearest_descriptor(const Descriptor& d, const Descriptor* candidates, int count, int* distance);

/// For each of the n descriptors in `data`, the index of the nearest of the k `centres` (first on
/// ties) written to out_index[i]. Returns how many entries of out_index changed value.
std::size_t assign_nearest(const Descriptor* data, std::size_t n, const Descriptor* centres, int k,
                           std::uint32_t* out_index);

/// min_sq_distance[i] = min(min_sq_distance[i], hamming(data[i], centre)^2) for the n descriptors;
/// returns the new sum of min_sq_distance (k-means++ seeding).
std::uint64_t update_min_squared_distance(const Descriptor* data, std::size_t n,
                                          const Descriptor& centre, std::uint32_t* min_sq_distance);

/// Throws ddl::Error unless `descriptors` is empty or N x 32 CV_8UC1 (a programming error, not a
/// per-frame outcome: the extractor always produces this layout).
void check_descriptor_mat(const cv::Mat& descriptors);

/// All rows of an N x 32 CV_8U matrix as Descriptors (checked as above).
std::vector<Descriptor> descriptors_from_mat(const cv::Mat& descriptors);

/// The descriptors as an N x 32 CV_8U matrix.
cv::Mat descriptors_to_mat(const std::vector<Descriptor>& descriptors);

}  // namespace ddl::vocabulary
