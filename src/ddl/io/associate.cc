#include "ddl/io/associate.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <tuple>

namespace ddl::io {

std::vector<StampMatch> associate(const std::vector<double>& first,
                                  const std::vector<double>& second, double offset,
                                  double max_difference) {
  // Candidates through a sorted view of `second`, so the cost is O(n log n + candidates) instead
  // of associate.py's O(n * m); the greedy order over candidates is the script's.
  std::vector<std::size_t> order(second.size());
  std::iota(order.begin(), order.end(), 0);
  std::vector<double> shifted(second.size());
  for (std::size_t j = 0; j < second.size(); ++j) shifted[j] = second[j] + offset;
  std::sort(order.begin(), order.end(),
            [&](std::size_t l, std::size_t r) { return shifted[l] < shifted[r]; });

  struct Candidate {
    double diff;
    double a;
    double b;
    std::size_t i;
    std::size_t j;
  };
  std::vector<Candidate> candidates;
  for (std::size_t i = 0; i < first.size(); ++i) {
    const double a = first[i];
    auto lo = std::lower_bound(order.begin(), order.end(), a - max_difference,
                               [&](std::size_t j, double v) { return shifted[j] < v; });
    for (auto it = lo; it != order.end() && shifted[*it] <= a + max_difference; ++it) {
      const double diff = std::abs(a - shifted[*it]);
      if (diff < max_difference) candidates.push_back({diff, a, second[*it], i, *it});
    }
  }
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& l, const Candidate& r) {
    return std::tie(l.diff, l.a, l.b) < std::tie(r.diff, r.a, r.b);
  });

  std::vector<bool> used_first(first.size(), false);
  std::vector<bool> used_second(second.size(), false);
  std::vector<StampMatch> matches;
  for (const Candidate& c : candidates) {
    if (used_first[c.i] || used_second[c.j]) continue;
    used_first[c.i] = true;
    used_second[c.j] = true;
    matches.push_back({c.i, c.j});
  }
  std::sort(matches.begin(), matches.end(), [&](const StampMatch& l, const StampMatch& r) {
    return std::tie(first[l.first], second[l.second]) < std::tie(first[r.first], second[r.second]);
  });
  return matches;
}

}  // namespace ddl::io
