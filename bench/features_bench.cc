// Micro-benchmarks of the ORB front end (docs/features.md):
//   ddl_bench_features --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// Uses the first RGB frame of ../shared/data/tum/rgbd_dataset_freiburg1_rpy (or $DDL_SHARED_DIR)
// when present, else a synthetic textured 640x480 image. The argument of the extraction
// benchmarks is OpenCV's thread count (cv::setNumThreads) for resize/blur inside the extractor.

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <random>
#include <string>

#include "ddl/features/feature_grid.h"
#include "ddl/features/matcher.h"
#include "ddl/features/orb_extractor.h"

namespace {

namespace fs = std::filesystem;
using ddl::features::OrbExtractor;
using ddl::features::OrbExtractorConfig;

fs::path shared_dir() {
  if (const char* env = std::getenv("DDL_SHARED_DIR"); env != nullptr && *env != '\0') return env;
  return fs::path(DDL_SOURCE_DIR) / ".." / "shared";
}

// Frame `index` of fr1_rpy in rgb.txt order, grayscale; empty when absent.
cv::Mat tum_frame(int index) {
  const fs::path dir = shared_dir() / "data" / "tum" / "rgbd_dataset_freiburg1_rpy";
  std::ifstream in(dir / "rgb.txt");
  std::string line;
  int seen = 0;
  while (std::getline(in, line)) {
    if (line.empty() || line[0] == '#') continue;
    if (seen++ == index) {
      return cv::imread((dir / line.substr(line.find(' ') + 1)).string(), cv::IMREAD_GRAYSCALE);
    }
  }
  return {};
}

cv::Mat synthetic_image(std::uint64_t seed) {
  cv::RNG rng(seed);
  cv::Mat image(480, 640, CV_8UC1, cv::Scalar(128));
  for (int k = 0; k < 600; ++k) {
    const cv::Point c(rng.uniform(0, 640), rng.uniform(0, 480));
    const int s = rng.uniform(4, 80);
    if (k % 2 == 0) {
      cv::rectangle(image, cv::Rect(c.x, c.y, s, rng.uniform(4, 80)),
                    cv::Scalar(rng.uniform(0, 256)), cv::FILLED);
    } else {
      cv::circle(image, c, s / 2, cv::Scalar(rng.uniform(0, 256)), cv::FILLED, cv::LINE_AA);
    }
  }
  cv::GaussianBlur(image, image, cv::Size(3, 3), 0.7);
  return image;
}

// The fr1_rpy frame, or the synthetic image if the data is absent (label says which).
const cv::Mat& bench_image(benchmark::State& state, int index = 0) {
  static const cv::Mat tum0 = tum_frame(0);
  static const cv::Mat tum1 = tum_frame(1);
  static const cv::Mat syn0 = synthetic_image(1);
  static const cv::Mat syn1 = synthetic_image(2);
  const cv::Mat& tum = index == 0 ? tum0 : tum1;
  state.SetLabel(tum.empty() ? "synthetic 640x480" : "fr1_rpy 640x480");
  return tum.empty() ? (index == 0 ? syn0 : syn1) : tum;
}

void BM_OrbExtract(benchmark::State& state, const cv::Mat* fixed_image, int extractor_threads) {
  cv::setNumThreads(static_cast<int>(state.range(0)));
  const cv::Mat& image = fixed_image != nullptr ? *fixed_image : bench_image(state);
  OrbExtractorConfig config;
  config.num_threads = extractor_threads;
  OrbExtractor extractor(config);
  std::size_t keypoints = 0;
  for (auto _ : state) {
    auto features = extractor.extract(image);
    keypoints = features.keypoints.size();
    benchmark::DoNotOptimize(features.descriptors.data);
  }
  state.counters["keypoints"] = static_cast<double>(keypoints);
  cv::setNumThreads(-1);
}

void BM_OrbExtractTum(benchmark::State& state) { BM_OrbExtract(state, nullptr, 1); }
void BM_OrbExtractTumLevelsParallel(benchmark::State& state) { BM_OrbExtract(state, nullptr, 2); }
void BM_OrbExtractSynthetic(benchmark::State& state) {
  static const cv::Mat image = synthetic_image(1);
  state.SetLabel("synthetic 640x480");
  BM_OrbExtract(state, &image, 1);
}
void BM_OrbExtractTumWithMask(benchmark::State& state) {
  cv::setNumThreads(static_cast<int>(state.range(0)));
  const cv::Mat& image = bench_image(state);
  cv::Mat mask(image.size(), CV_8UC1, cv::Scalar(0));
  mask(cv::Rect(200, 100, 200, 300)).setTo(255);
  OrbExtractor extractor{OrbExtractorConfig{}};
  for (auto _ : state) benchmark::DoNotOptimize(extractor.extract(image, mask).descriptors.data);
  cv::setNumThreads(-1);
}
// Argument: OpenCV threads (1 = everything on the calling thread). CPU time is that of the whole
// process, so work on helper threads counts.
BENCHMARK(BM_OrbExtractTum)
    ->Arg(1)
    ->Arg(2)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OrbExtractTumLevelsParallel)
    ->Arg(1)
    ->Arg(2)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OrbExtractSynthetic)
    ->Arg(1)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);
BENCHMARK(BM_OrbExtractTumWithMask)
    ->Arg(1)
    ->MeasureProcessCPUTime()
    ->UseRealTime()
    ->Unit(benchmark::kMillisecond);

void BM_MatchBruteForce(benchmark::State& state) {
  cv::setNumThreads(1);
  OrbExtractor extractor{OrbExtractorConfig{}};
  const auto a = extractor.extract(bench_image(state, 0));
  const auto b = extractor.extract(bench_image(state, 1));
  std::size_t matches = 0;
  for (auto _ : state) {
    const auto m = ddl::features::match_brute_force(a.descriptors, b.descriptors);
    matches = m.size();
    benchmark::DoNotOptimize(m.data());
  }
  state.counters["query"] = a.descriptors.rows;
  state.counters["train"] = b.descriptors.rows;
  state.counters["matches"] = static_cast<double>(matches);
  cv::setNumThreads(-1);
}
BENCHMARK(BM_MatchBruteForce)->Unit(benchmark::kMillisecond);

void BM_MatchWithRotationFilter(benchmark::State& state) {
  cv::setNumThreads(1);
  OrbExtractor extractor{OrbExtractorConfig{}};
  const auto a = extractor.extract(bench_image(state, 0));
  const auto b = extractor.extract(bench_image(state, 1));
  for (auto _ : state) {
    const auto m = ddl::features::filter_by_rotation(
        ddl::features::match_brute_force(a.descriptors, b.descriptors), a.keypoints, b.keypoints);
    benchmark::DoNotOptimize(m.data());
  }
  cv::setNumThreads(-1);
}
BENCHMARK(BM_MatchWithRotationFilter)->Unit(benchmark::kMillisecond);

// The inline distance used by projection matching (portable build: bit-twiddling popcount
// unless compiled with -mpopcnt / DDL_NATIVE).
void BM_HammingDistance(benchmark::State& state) {
  std::mt19937 rng(1);
  cv::Mat d(1024, ddl::features::kDescriptorBytes, CV_8UC1);
  cv::randu(d, 0, 256);
  int sum = 0;
  for (auto _ : state) {
    for (int i = 0; i < 1024; i += 2) sum += ddl::features::hamming_distance(d, i, d, i + 1);
    benchmark::DoNotOptimize(sum);
  }
  state.SetItemsProcessed(state.iterations() * 512);
}
BENCHMARK(BM_HammingDistance);

void BM_FeatureGridQuery(benchmark::State& state) {
  OrbExtractor extractor{OrbExtractorConfig{}};
  const auto f = extractor.extract(bench_image(state));
  const ddl::features::FeatureGrid grid(f.keypoints, cv::Rect2f(0, 0, 640, 480));
  std::vector<std::size_t> out;
  std::size_t found = 0;
  for (auto _ : state) {
    for (const cv::KeyPoint& kp : f.keypoints) {
      grid.features_in_area(kp.pt.x + 3.0f, kp.pt.y - 2.0f, 15.0f, 0, 7,
                            ddl::features::SearchWindow::kSquare, out);
      found += out.size();
    }
    benchmark::DoNotOptimize(found);
  }
  state.SetItemsProcessed(state.iterations() * static_cast<std::int64_t>(f.keypoints.size()));
}
BENCHMARK(BM_FeatureGridQuery)->Unit(benchmark::kMicrosecond);

void BM_FeatureGridBuild(benchmark::State& state) {
  OrbExtractor extractor{OrbExtractorConfig{}};
  const auto f = extractor.extract(bench_image(state));
  for (auto _ : state) {
    const ddl::features::FeatureGrid grid(f.keypoints, cv::Rect2f(0, 0, 640, 480));
    benchmark::DoNotOptimize(grid.size());
  }
}
BENCHMARK(BM_FeatureGridBuild)->Unit(benchmark::kMicrosecond);

}  // namespace

BENCHMARK_MAIN();
