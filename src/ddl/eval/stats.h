#pragma once
// Summary statistics of an error sample, computed with numpy's conventions so that they equal the
// numbers TUM's evaluate_ate.py / evaluate_rpe.py print: rmse = sqrt(dot(e, e) / n), mean,
// median (numpy.median: mean of the two middle values for even n), std (numpy.std: population
// standard deviation, divisor n), min and max.

#include <cstddef>
#include <vector>

namespace ddl::eval {

struct ErrorStats {
  std::size_t count = 0;
  double rmse = 0.0;
  double mean = 0.0;
  double median = 0.0;
  double std = 0.0;  // population standard deviation (numpy.std, ddof = 0)
  double min = 0.0;
  double max = 0.0;

  /// Every statistic multiplied by `factor` (e.g. radians to degrees); count unchanged.
  ErrorStats scaled(double factor) const;
};

/// Statistics of `values`. An empty sample gives count 0 and NaN for every statistic.
ErrorStats compute_stats(const std::vector<double>& values);

/// numpy.median of `values` (NaN when empty).
double numpy_median(std::vector<double> values);

}  // namespace ddl::eval
