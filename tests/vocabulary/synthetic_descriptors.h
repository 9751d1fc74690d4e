#pragma once
// Synthetic binary descriptors for the vocabulary tests: random prototypes ("visual words" of a
// made-up world) and noisy observations of them. std::mt19937_64's raw output is fully specified
// by the standard, so every test sees the same numbers on every platform.

#include <cstdint>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "ddl/vocabulary/descriptor.h"

namespace ddl::vocabulary::test {

inline Descriptor random_descriptor(std::mt19937_64& rng) {
  return Descriptor{rng(), rng(), rng(), rng()};
}

/// `d` with `bits` distinct random bits flipped.
inline Descriptor flip_bits(Descriptor d, int bits, std::mt19937_64& rng) {
  std::vector<int> flipped;
  while (static_cast<int>(flipped.size()) < bits) {
    const int b = static_cast<int>(rng() % kDescriptorBits);
    bool seen = false;
    for (int f : flipped) seen = seen || f == b;
    if (seen) continue;
    flipped.push_back(b);
    d[b / 64] ^= std::uint64_t{1} << (b % 64);
  }
  return d;
}

inline std::vector<Descriptor> random_descriptors(std::size_t n, std::mt19937_64& rng) {
  std::vector<Descriptor> out(n);
  for (Descriptor& d : out) d = random_descriptor(rng);
  return out;
}

/// An "image": `count` observations of prototypes drawn at random, each with `noise_bits` flipped.
inline std::vector<Descriptor> random_image(const std::vector<Descriptor>& prototypes,
                                            std::size_t count, int noise_bits,
                                            std::mt19937_64& rng) {
  std::vector<Descriptor> out(count);
  for (Descriptor& d : out) d = flip_bits(prototypes[rng() % prototypes.size()], noise_bits, rng);
  return out;
}

/// Re-observation of an image: each descriptor kept with probability keep_percent / 100 and
/// `noise_bits` of it flipped.
inline std::vector<Descriptor> reobserve(const std::vector<Descriptor>& image, int keep_percent,
                                         int noise_bits, std::mt19937_64& rng) {
  std::vector<Descriptor> out;
  for (const Descriptor& d : image) {
    if (static_cast<int>(rng() % 100) < keep_percent) out.push_back(flip_bits(d, noise_bits, rng));
  }
  return out;
}

}  // namespace ddl::vocabulary::test
