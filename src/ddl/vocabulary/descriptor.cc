#include "ddl/vocabulary/descriptor.h"

#include <fmt/format.h>

#include "ddl/core/error.h"

namespace ddl::vocabulary {

namespace {

// The kernels' bodies, inlined both into a generic build and into one compiled for the POPCNT
// instruction (x86-64 builds without -mpopcnt, i.e. portable ones), chosen at run time. Plain
// run-time dispatch rather than ifunc/target_clones, which crash under ThreadSanitizer.
[[gnu::always_inline]] inline int nearest_impl(const Descriptor& d, const Descriptor* candidates,
                                               int count, int* distance) {
  int best = 0;
  int best_distance = hamming_distance(d, candidates[0]);
  for (int c = 1; c < count; ++c) {
    const int dist = hamming_distance(d, candidates[c]);
    if (dist < best_distance) {
      best_distance = dist;
      best = c;
    }
  }
  if (distance != nullptr) *distance = best_distance;
  return best;
}

[[gnu::always_inline]] inline std::size_t assign_impl(const Descriptor* data, std::size_t n,
                                                      const Descriptor* centres, int k,
                                                      std::uint32_t* out_index) {
  std::size_t changed = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto best = static_cast<std::uint32_t>(nearest_impl(data[i], centres, k, nullptr));
    if (out_index[i] != best) {
      out_index[i] = best;
      ++changed;
    }
  }
  return changed;
}

[[gnu::always_inline]] inline std::uint64_t update_impl(const Descriptor* data, std::size_t n,
                                                        const Descriptor& centre,
                                                        std::uint32_t* min_sq_distance) {
  std::uint64_t sum = 0;
  for (std::size_t i = 0; i < n; ++i) {
    const auto dist = static_cast<std::uint32_t>(hamming_distance(data[i], centre));
    const std::uint32_t sq = dist * dist;
    if (sq < min_sq_distance[i]) min_sq_distance[i] = sq;
    sum += min_sq_distance[i];
  }
  return sum;
}

#if defined(__x86_64__) && defined(__GNUC__) && !defined(__POPCNT__)
#define DDL_POPCNT_DISPATCH 1

bool cpu_has_popcnt() {
  static const bool has = __builtin_cpu_supports("popcnt") != 0;
  return has;
}

[[gnu::target("popcnt")]] int nearest_popcnt(const Descriptor& d, const Descriptor* candidates,
                                             int count, int* distance) {
  return nearest_impl(d, candidates, count, distance);
}

[[gnu::target("popcnt")]] std::size_t assign_popcnt(const Descriptor* data, std::size_t n,
                                                    const Descriptor* centres, int k,
                                                    std::uint32_t* out_index) {
  return assign_impl(data, n, centres, k, out_index);
}

[[gnu::target("popcnt")]] std::uint64_t update_popcnt(const Descriptor* data, std::size_t n,
                                                      const Descriptor& centre,
                                                      std::uint32_t* min_sq_distance) {
  return update_impl(data, n, centre, min_sq_distance);
}
#else
#define DDL_POPCNT_DISPATCH 0
#endif

}  // namespace

int nearest_descriptor(const Descriptor& d, const Descriptor* candidates, int count,
                       int* distance) {
#if DDL_POPCNT_DISPATCH
  if (cpu_has_popcnt()) return nearest_popcnt(d, candidates, count, distance);
#endif
  return nearest_impl(d, candidates, count, distance);
}

std::size_t assign_nearest(const Descriptor* data, std::size_t n, const Descriptor* centres, int k,
                           std::uint32_t* out_index) {
#if DDL_POPCNT_DISPATCH
  if (cpu_has_popcnt()) return assign_popcnt(data, n, centres, k, out_index);
#endif
  return assign_impl(data, n, centres, k, out_index);
}

std::uint64_t update_min_squared_distance(const Descriptor* data, std::size_t n,
                                          const Descriptor& centre,
                                          std::uint32_t* min_sq_distance) {
#if DDL_POPCNT_DISPATCH
  if (cpu_has_popcnt()) return update_popcnt(data, n, centre, min_sq_distance);
#endif
  return update_impl(data, n, centre, min_sq_distance);
}

void check_descriptor_mat(const cv::Mat& descriptors) {
  if (descriptors.empty()) return;
  if (descriptors.type() != CV_8UC1 || descriptors.cols != kDescriptorBytes) {
    throw Error(fmt::format(
        "binary descriptors must be an N x {} CV_8UC1 matrix, got {} x {} of OpenCV type {}",
        kDescriptorBytes, descriptors.rows, descriptors.cols, descriptors.type()));
  }
}

std::vector<Descriptor> descriptors_from_mat(const cv::Mat& descriptors) {
  check_descriptor_mat(descriptors);
  std::vector<Descriptor> out(static_cast<std::size_t>(descriptors.rows));
  for (int r = 0; r < descriptors.rows; ++r) {
    out[static_cast<std::size_t>(r)] = descriptor_from_bytes(descriptors.ptr<std::uint8_t>(r));
  }
  return out;
}

cv::Mat descriptors_to_mat(const std::vector<Descriptor>& descriptors) {
  cv::Mat out(static_cast<int>(descriptors.size()), kDescriptorBytes, CV_8UC1);
  for (int r = 0; r < out.rows; ++r) {
    descriptor_to_bytes(descriptors[static_cast<std::size_t>(r)], out.ptr<std::uint8_t>(r));
  }
  return out;
}

}  // namespace ddl::vocabulary
