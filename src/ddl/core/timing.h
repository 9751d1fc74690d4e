#pragma once
// Wall-clock stage timing: a Stopwatch, and TimingStats collecting per-stage samples whose
// medians go into every run summary. TimingStats is thread-safe (stages on several threads record
// into one instance).

#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <vector>

namespace ddl {

class Stopwatch {
 public:
  Stopwatch() : start_(Clock::now()) {}
  void reset() { start_ = Clock::now(); }
  double elapsed_ms() const {
    return std::chrono::duration<double, std::milli>(Clock::now() - start_).count();
  }

 private:
  using Clock = std::chrono::steady_clock;
  Clock::time_point start_;
};

/// CPU time used so far by the calling thread / by the whole process, in milliseconds: what a
/// stage costs, independent of other processes competing for the cores (wall time is not).
double thread_cpu_ms();
double process_cpu_ms();

struct StageSummary {
  std::size_t count = 0;
  double median_ms = 0.0;
  double mean_ms = 0.0;
  double p90_ms = 0.0;
  double max_ms = 0.0;
  double total_ms = 0.0;
};

class TimingStats {
 public:
  void record(const std::string& stage, double ms);
  std::map<std::string, StageSummary> summary() const;
  std::vector<double> samples(const std::string& stage) const;

 private:
  mutable std::mutex mutex_;
  std::map<std::string, std::vector<double>> samples_;
};

/// Median of a sample (mean of the two middle values for even sizes, as numpy.median). 0 if empty.
double median(std::vector<double> values);

}  // namespace ddl
