#include "ddl/features/brief_pattern.h"

#include <algorithm>
#include <cmath>
#include <numbers>
#include <set>
#include <tuple>

namespace ddl::features {
namespace {

// SplitMix64 (Steele, Lea & Flood, OOPSLA 2014): a tiny generator with a fully specified output
// sequence.
class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ULL);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ULL;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBULL;
    return z ^ (z >> 31);
  }
  /// Uniform in (0, 1): 53 random bits, offset by half a step so 0 never occurs.
  double uniform_open() { return (static_cast<double>(next() >> 11) + 0.5) * 0x1.0p-53; }

 private:
  std::uint64_t state_;
};

// Box-Muller: one standard normal sample per call (the sine half is discarded, which keeps the
// sequence simple to describe).
double standard_normal(SplitMix64& rng) {
  const double u1 = rng.uniform_open();
  const double u2 = rng.uniform_open();
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

constexpr BriefPattern kLearnedPattern = {{
#include "ddl/features/brief_pattern_table.inc"
}};

}  // namespace

std::vector<BriefPair> make_random_pairs(std::uint64_t seed, int count,
                                         PairDistribution distribution, int patch_size) {
  SplitMix64 rng(seed);
  const double sigma = patch_size / 5.0;  // BRIEF G II: variance S^2 / 25
  const long radius = patch_size / 2;
  auto draw_point = [&](std::int8_t& x, std::int8_t& y) {
    for (;;) {
      long px = 0;
      long py = 0;
      if (distribution == PairDistribution::kGaussian) {
        px = std::lround(sigma * standard_normal(rng));
        py = std::lround(sigma * standard_normal(rng));
      } else {
        const double side = 2.0 * radius + 1.0;
        px = static_cast<long>(std::floor(rng.uniform_open() * side)) - radius;
        py = static_cast<long>(std::floor(rng.uniform_open() * side)) - radius;
      }
      if (px * px + py * py <= radius * radius) {
        x = static_cast<std::int8_t>(px);
        y = static_cast<std::int8_t>(py);
        return;
      }
    }
  };
  // A test and its mirror (points swapped) carry the same information.
  auto key = [](const BriefPair& p) {
    const auto a = std::make_tuple(p.x1, p.y1, p.x2, p.y2);
    const auto b = std::make_tuple(p.x2, p.y2, p.x1, p.y1);
    return std::min(a, b);
  };
  std::set<std::tuple<std::int8_t, std::int8_t, std::int8_t, std::int8_t>> seen;
  std::vector<BriefPair> pairs;
  pairs.reserve(static_cast<std::size_t>(std::max(count, 0)));
  while (static_cast<int>(pairs.size()) < count) {
    BriefPair pair;
    draw_point(pair.x1, pair.y1);
    draw_point(pair.x2, pair.y2);
    if (pair.x1 == pair.x2 && pair.y1 == pair.y2) continue;
    if (!seen.insert(key(pair)).second) continue;
    pairs.push_back(pair);
  }
  return pairs;
}

BriefPattern make_gaussian_pattern(std::uint64_t seed, int patch_size) {
  const std::vector<BriefPair> pairs =
      make_random_pairs(seed, kDescriptorBits, PairDistribution::kGaussian, patch_size);
  BriefPattern pattern;
  std::copy(pairs.begin(), pairs.end(), pattern.begin());
  return pattern;
}

const BriefPattern& default_brief_pattern() { return kLearnedPattern; }

double pattern_radius(const BriefPattern& pattern) {
  int max_r2 = 0;
  for (const BriefPair& p : pattern) {
    max_r2 = std::max({max_r2, p.x1 * p.x1 + p.y1 * p.y1, p.x2 * p.x2 + p.y2 * p.y2});
  }
  return std::sqrt(static_cast<double>(max_r2));
}

}  // namespace ddl::features
