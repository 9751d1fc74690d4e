// Vocabulary micro-benchmarks: descriptor-to-word transform (1000 descriptors, the features of
// one frame), BoW scoring, database query and the load time of a vocabulary file.
//
// The vocabulary is $DDL_VOCABULARY if set, else the default vocab/ddl_orb_k10_l5.dvoc of the
// source tree; without either file, the transform benchmarks use a k=10 L=5 vocabulary trained
// here on synthetic descriptors (the label says which) and the load benchmark is skipped.

#include <benchmark/benchmark.h>

#include <cstdlib>
#include <filesystem>
#include <memory>
#include <random>
#include <string>

#include "ddl/vocabulary/bow_database.h"
#include "ddl/vocabulary/vocabulary.h"
#include "ddl/vocabulary/vocabulary_training.h"

namespace {

using namespace ddl::vocabulary;

std::string vocabulary_path() {
  if (const char* env = std::getenv("DDL_VOCABULARY"); env != nullptr && *env != '\0') return env;
  return std::string(DDL_SOURCE_DIR) + "/vocab/ddl_orb_k10_l5.dvoc";
}

std::vector<Descriptor> random_descriptors(std::size_t n, std::uint64_t seed) {
  std::mt19937_64 rng(seed);
  std::vector<Descriptor> out(n);
  for (Descriptor& d : out) d = Descriptor{rng(), rng(), rng(), rng()};
  return out;
}

// The file vocabulary, or a synthetic one trained once.
const Vocabulary& bench_vocabulary(std::string* label) {
  static const auto loaded = [] {
    auto v = std::make_unique<Vocabulary>();
    std::string name;
    if (std::filesystem::exists(vocabulary_path())) {
      *v = Vocabulary::load(vocabulary_path());
      name = std::filesystem::path(vocabulary_path()).filename().string();
    } else {
      std::vector<cv::Mat> images;
      for (int i = 0; i < 200; ++i) {
        images.push_back(descriptors_to_mat(random_descriptors(1000, 100 + i)));
      }
      VocabularyConfig config;
      config.levels = 5;
      *v = train_vocabulary(images, config);
      name = "synthetic k10 L5";
    }
    return std::make_pair(std::move(v), name);
  }();
  *label = loaded.second;
  return *loaded.first;
}

void BM_Transform1000(benchmark::State& state) {
  std::string label;
  const Vocabulary& voc = bench_vocabulary(&label);
  const cv::Mat d = descriptors_to_mat(random_descriptors(1000, 1));
  for (auto _ : state) benchmark::DoNotOptimize(voc.transform(d));
  state.SetLabel(label);
  state.SetItemsProcessed(state.iterations() * 1000);
}
BENCHMARK(BM_Transform1000)->Unit(benchmark::kMicrosecond);

void BM_Transform1000WithFeatureVector(benchmark::State& state) {
  std::string label;
  const Vocabulary& voc = bench_vocabulary(&label);
  const cv::Mat d = descriptors_to_mat(random_descriptors(1000, 1));
  BowVector bow;
  FeatureVector features;
  for (auto _ : state) {
    voc.transform(d, 4, bow, features);
    benchmark::DoNotOptimize(bow);
    benchmark::DoNotOptimize(features);
  }
  state.SetLabel(label);
  state.SetItemsProcessed(state.iterations() * 1000);
}
BENCHMARK(BM_Transform1000WithFeatureVector)->Unit(benchmark::kMicrosecond);

void BM_L1Score(benchmark::State& state) {
  std::string label;
  const Vocabulary& voc = bench_vocabulary(&label);
  const BowVector a = voc.transform(random_descriptors(1000, 2));
  const BowVector b = voc.transform(random_descriptors(1000, 3));
  for (auto _ : state) benchmark::DoNotOptimize(l1_score(a, b));
  state.SetLabel(label);
}
BENCHMARK(BM_L1Score)->Unit(benchmark::kMicrosecond);

// A database of 300 keyframe vectors (a long sequence's keyframes), one query.
void BM_DatabaseQuery300(benchmark::State& state) {
  std::string label;
  const Vocabulary& voc = bench_vocabulary(&label);
  BowDatabase db;
  for (EntryId id = 0; id < 300; ++id) db.add(id, voc.transform(random_descriptors(1000, 10 + id)));
  const BowVector q = voc.transform(random_descriptors(1000, 5));
  for (auto _ : state) benchmark::DoNotOptimize(db.query(q, 10));
  state.SetLabel(label);
}
BENCHMARK(BM_DatabaseQuery300)->Unit(benchmark::kMicrosecond);

void BM_LoadVocabulary(benchmark::State& state) {
  const std::string path = vocabulary_path();
  if (!std::filesystem::exists(path)) {
    state.SkipWithError(("no vocabulary file at " + path + " (set DDL_VOCABULARY)").c_str());
    return;
  }
  std::size_t nodes = 0;
  for (auto _ : state) {
    const Vocabulary v = Vocabulary::load(path);
    nodes = v.node_count();
    benchmark::DoNotOptimize(nodes);
  }
  state.SetLabel(std::filesystem::path(path).filename().string() + ", " + std::to_string(nodes) +
                 " nodes");
}
BENCHMARK(BM_LoadVocabulary)->Unit(benchmark::kMillisecond)->Iterations(5);

}  // namespace

BENCHMARK_MAIN();
