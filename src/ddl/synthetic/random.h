#pragma once
// Deterministic random numbers for the generator. Everything random in a synthetic sequence comes
// from these functions, seeded by the sequence seed, so the same seed gives the same bytes on every
// run and platform: SplitMix64 (Steele, Lea, Flood 2014) as a stateful generator for scene layout,
// and as a counter-based hash for per-pixel noise (any pixel's noise is a pure function of
// (seed, frame, pixel), so rows can be processed in parallel in any order). No std::*_distribution
// is used: their output is implementation-defined.

#include <cmath>
#include <cstdint>

namespace ddl::synthetic {

/// The SplitMix64 finaliser: a bijective 64-bit mix with good avalanche.
constexpr std::uint64_t mix64(std::uint64_t z) {
  z += 0x9e3779b97f4a7c15ULL;
  z = (z ^ (z >> 30U)) * 0xbf58476d1ce4e5b9ULL;
  z = (z ^ (z >> 27U)) * 0x94d049bb133111ebULL;
  return z ^ (z >> 31U);
}

/// Hash of a pair of values (order matters).
constexpr std::uint64_t hash2(std::uint64_t a, std::uint64_t b) { return mix64(a ^ mix64(b)); }
constexpr std::uint64_t hash3(std::uint64_t a, std::uint64_t b, std::uint64_t c) {
  return hash2(hash2(a, b), c);
}

/// Uniform in [0, 1) from the top 53 bits of a hash.
inline double unit_from_hash(std::uint64_t h) {
  return static_cast<double>(h >> 11U) * (1.0 / 9007199254740992.0);
}

/// Approximately standard normal from one hash: the sum of four 16-bit uniforms (Irwin-Hall,
/// variance-normalised; tails end at +-3.46 sigma, enough for sensor noise and much cheaper than
/// Box-Muller per pixel).
inline float gauss_from_hash(std::uint64_t h) {
  const std::uint32_t s =
      static_cast<std::uint32_t>(h & 0xffffU) + static_cast<std::uint32_t>((h >> 16U) & 0xffffU) +
      static_cast<std::uint32_t>((h >> 32U) & 0xffffU) + static_cast<std::uint32_t>(h >> 48U);
  // Mean 2 * 65535, standard deviation 65536 * sqrt(4 / 12).
  return (static_cast<float>(s) - 131070.0f) * (1.0f / 37837.23f);
}

/// Stateful SplitMix64 generator for scene construction (layout, textures, paths).
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : state_(mix64(seed ^ 0x5851f42d4c957f2dULL)) {}
  std::uint64_t next() {
    state_ += 0x9e3779b97f4a7c15ULL;
    return mix64(state_);
  }
  /// Uniform in [0, 1).
  double uniform() { return unit_from_hash(next()); }
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Uniform integer in [lo, hi] (inclusive).
  int uniform_int(int lo, int hi) {
    const auto span = static_cast<std::uint64_t>(hi - lo + 1);
    return lo + static_cast<int>(next() % span);
  }
  /// Standard normal (Box-Muller; std::log/std::cos are correctly rounded enough on glibc).
  double normal() {
    const double u1 = 1.0 - uniform();
    const double u2 = uniform();
    return std::sqrt(-2.0 * std::log(u1)) * std::cos(6.283185307179586 * u2);
  }
  /// A derived generator, e.g. one per texture, so adding a texture leaves the others unchanged.
  Rng fork(std::uint64_t salt) { return Rng(hash2(next(), salt)); }

 private:
  std::uint64_t state_;
};

}  // namespace ddl::synthetic
