#include "ddl/core/timing.h"

#include <time.h>

#include <algorithm>
#include <numeric>

namespace ddl {
namespace {

double clock_ms(clockid_t clock) {
  timespec t{};
  clock_gettime(clock, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

}  // namespace

double thread_cpu_ms() { return clock_ms(CLOCK_THREAD_CPUTIME_ID); }

double process_cpu_ms() { return clock_ms(CLOCK_PROCESS_CPUTIME_ID); }

double median(std::vector<double> values) {
  if (values.empty()) return 0.0;
  const std::size_t n = values.size();
  std::nth_element(values.begin(), values.begin() + n / 2, values.end());
  const double upper = values[n / 2];
  if (n % 2 == 1) return upper;
  const double lower = *std::max_element(values.begin(), values.begin() + n / 2);
  return 0.5 * (lower + upper);
}

void TimingStats::record(const std::string& stage, double ms) {
  std::lock_guard lock(mutex_);
  samples_[stage].push_back(ms);
}

std::vector<double> TimingStats::samples(const std::string& stage) const {
  std::lock_guard lock(mutex_);
  auto it = samples_.find(stage);
  return it == samples_.end() ? std::vector<double>{} : it->second;
}

std::map<std::string, StageSummary> TimingStats::summary() const {
  std::lock_guard lock(mutex_);
  std::map<std::string, StageSummary> out;
  for (const auto& [stage, values] : samples_) {
    StageSummary s;
    s.count = values.size();
    if (!values.empty()) {
      std::vector<double> sorted = values;
      std::sort(sorted.begin(), sorted.end());
      s.median_ms = median(values);
      s.total_ms = std::accumulate(values.begin(), values.end(), 0.0);
      s.mean_ms = s.total_ms / static_cast<double>(values.size());
      s.p90_ms = sorted[std::min(sorted.size() - 1, (sorted.size() * 9) / 10)];
      s.max_ms = sorted.back();
    }
    out[stage] = s;
  }
  return out;
}

}  // namespace ddl
