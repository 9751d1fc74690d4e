#pragma once
// Timestamp association exactly as the TUM RGB-D benchmark's associate.py: every pair (a, b) with
// |a - (b + offset)| < max_difference is a candidate; candidates are taken greedily by smallest
// difference (ties by a, then b, as Python sorts tuples), each stamp used at most once; the result
// is sorted by a. Used for RGB/depth pairing and for ground-truth/estimate matching in evaluation.

#include <cstddef>
#include <utility>
#include <vector>

namespace ddl::io {

struct StampMatch {
  std::size_t first;   // index into the first stamp list
  std::size_t second;  // index into the second stamp list
};

/// Stamps need not be sorted; duplicate stamps must already be removed by the caller (TUM's
/// scripts read files into a dict, so a later line with the same stamp replaces an earlier one).
std::vector<StampMatch> associate(const std::vector<double>& first,
                                  const std::vector<double>& second, double offset = 0.0,
                                  double max_difference = 0.02);

}  // namespace ddl::io
