#include "ddl/eval/stats.h"

#include <algorithm>
#include <cmath>
#include <limits>

namespace ddl::eval {

ErrorStats ErrorStats::scaled(double factor) const {
  ErrorStats out = *this;
  out.rmse *= factor;
  out.mean *= factor;
  out.median *= factor;
  out.std *= factor;
  out.min *= factor;
  out.max *= factor;
  return out;
}

double numpy_median(std::vector<double> values) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  const std::size_t n = values.size();
  const std::size_t mid = n / 2;
  std::nth_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid), values.end());
  const double upper = values[mid];
  if (n % 2 == 1) return upper;
  const double lower =
      *std::max_element(values.begin(), values.begin() + static_cast<std::ptrdiff_t>(mid));
  // numpy.median takes numpy.mean of the two middle values: (lower + upper) / 2.
  return (lower + upper) / 2.0;
}

ErrorStats compute_stats(const std::vector<double>& values) {
  ErrorStats s;
  s.count = values.size();
  if (values.empty()) {
    const double nan = std::numeric_limits<double>::quiet_NaN();
    s.rmse = s.mean = s.median = s.std = s.min = s.max = nan;
    return s;
  }
  const double n = static_cast<double>(values.size());
  double sum = 0.0;
  double sum_sq = 0.0;
  s.min = values.front();
  s.max = values.front();
  for (double v : values) {
    sum += v;
    sum_sq += v * v;
    s.min = std::min(s.min, v);
    s.max = std::max(s.max, v);
  }
  s.rmse = std::sqrt(sum_sq / n);
  s.mean = sum / n;
  // Two-pass population variance, as numpy.std computes it (mean of squared deviations).
  double dev_sq = 0.0;
  for (double v : values) dev_sq += (v - s.mean) * (v - s.mean);
  s.std = std::sqrt(dev_sq / n);
  s.median = numpy_median(values);
  return s;
}

}  // namespace ddl::eval
