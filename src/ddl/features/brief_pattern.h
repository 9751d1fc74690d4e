#pragma once
// The point-pair sampling pattern of the steered BRIEF descriptor (Calonder et al., ECCV 2010;
// Rublee et al., ICCV 2011).
//
// Provenance (docs/features.md): every pair comes from our own seeded generator,
// make_random_pairs(), with SplitMix64 and Box-Muller written here so the sequence is the same on
// every platform. Points are drawn either i.i.d. from an isotropic Gaussian N(0, (S/5)^2),
// S = patch size (the BRIEF paper's strategy G II), or uniformly over the integer points of the
// disc of radius S/2 (strategy G I); a Gaussian point outside that disc is drawn again (so the
// pattern stays inside the patch at any rotation), as is a pair whose points coincide or that
// repeats an earlier pair in either order.
//
// Random tests are strongly biased once steered by the keypoint orientation (ORB section 4.2),
// so the default pattern is the 256 tests that pattern_learning.h's greedy search (ORB section
// 4.3) selected from 32768 uniform-disc pairs (seed kDefaultBriefPatternSeed) on 32346 keypoints
// of the 599 CCP photographs in ../shared/data/people; bench/learn_brief_pattern.cc wrote the
// table (brief_pattern_table.inc), which is compiled in. No table of another project was used.

#include <array>
#include <cstdint>
#include <vector>

namespace ddl::features {

/// Seed of the candidate pairs the default pattern was selected from.
inline constexpr std::uint64_t kDefaultBriefPatternSeed = 0xD0D1'5EED'2020'0001ULL;

/// Number of binary tests (bits) of the descriptor, and its size in bytes.
inline constexpr int kDescriptorBits = 256;
inline constexpr int kDescriptorBytes = kDescriptorBits / 8;

/// One binary test: bit = I(x1, y1) < I(x2, y2), offsets in pixels from the keypoint, before the
/// rotation by the keypoint's orientation.
struct BriefPair {
  std::int8_t x1 = 0, y1 = 0, x2 = 0, y2 = 0;
  friend bool operator==(const BriefPair&, const BriefPair&) = default;
};

using BriefPattern = std::array<BriefPair, kDescriptorBits>;

/// Distribution of the points of random pairs (BRIEF paper, section 3.2).
enum class PairDistribution {
  kGaussian,     // G II: i.i.d. N(0, (S/5)^2) per coordinate, clipped to the patch disc
  kUniformDisc,  // G I: uniform over the integer points of the patch disc
};

/// `count` distinct pairs from the seeded generator described above, for `patch_size` (odd,
/// 7..63). Deterministic: the same arguments always give the same pairs, and a longer sequence
/// starts with the shorter one.
std::vector<BriefPair> make_random_pairs(std::uint64_t seed, int count,
                                         PairDistribution distribution, int patch_size = 31);

/// The first 256 Gaussian pairs of make_random_pairs(): an untrained pattern (BRIEF G II).
BriefPattern make_gaussian_pattern(std::uint64_t seed = kDefaultBriefPatternSeed,
                                   int patch_size = 31);

/// The project's descriptor pattern (patch size 31): learned as described above. Changing it
/// changes every descriptor, so vocabularies and maps made with one pattern are useless with
/// another.
const BriefPattern& default_brief_pattern();

/// Largest distance of a pattern point from the keypoint, in pixels.
double pattern_radius(const BriefPattern& pattern);

}  // namespace ddl::features
