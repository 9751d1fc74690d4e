#include "ddl/vocabulary/vocabulary_training.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <exception>
#include <limits>
#include <mutex>
#include <thread>

#include "ddl/core/error.h"
#include "ddl/core/timing.h"

namespace ddl::vocabulary {
namespace {

__extension__ using Uint128 = unsigned __int128;

// SplitMix64 (Steele, Lea & Flood 2014): tiny, fully specified, so a seed gives the same stream
// on every platform and standard library (std:: distributions are implementation-defined).
class SplitMix64 {
 public:
  explicit SplitMix64(std::uint64_t seed) : state_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (state_ += 0x9E3779B97F4A7C15ull);
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
  }
  /// Uniform in [0, bound), bound >= 1 (multiply-shift; the bias is < bound / 2^64).
  std::uint64_t below(std::uint64_t bound) {
    return static_cast<std::uint64_t>((static_cast<Uint128>(next()) * bound) >> 64);
  }

 private:
  std::uint64_t state_;
};

// Each node's k-means gets its own stream derived from the seed and its node id, so the result
// does not depend on the order in which threads pick up nodes.
std::uint64_t node_seed(std::uint64_t seed, NodeId node) {
  SplitMix64 mixer(seed ^ (0xD1B54A32D192ED03ull * (static_cast<std::uint64_t>(node) + 1)));
  mixer.next();
  return mixer.next();
}

struct Cluster {
  Descriptor centre{};
  std::vector<std::uint32_t> members;  // indices into the flattened training descriptors
};

struct SplitResult {
  std::vector<Cluster> clusters;
  std::size_t iterations = 0;
  bool hit_max_iterations = false;
};

// counts[b] += sign * bit b of d.
void add_bits(const Descriptor& d, std::int32_t* counts, std::int32_t sign) {
  for (int w = 0; w < 4; ++w) {
    const std::uint64_t x = d[w];
    std::int32_t* c = counts + 64 * w;
    for (int b = 0; b < 64; ++b) c[b] += sign * static_cast<std::int32_t>((x >> b) & 1u);
  }
}

// Per-bit majority vote of `size` descriptors whose bit sums are `counts` (ties give 1).
Descriptor majority(const std::int32_t* counts, std::int32_t size) {
  Descriptor d{};
  for (int w = 0; w < 4; ++w) {
    std::uint64_t x = 0;
    for (int b = 0; b < 64; ++b) {
      if (2 * counts[64 * w + b] >= size) x |= std::uint64_t{1} << b;
    }
    d[w] = x;
  }
  return d;
}

bool all_equal(const std::vector<Descriptor>& all, const std::vector<std::uint32_t>& members) {
  for (std::uint32_t m : members) {
    if (all[m] != all[members.front()]) return false;
  }
  return true;
}

// One child per distinct descriptor (in order of first occurrence), for nodes with <= k members.
SplitResult split_distinct(const std::vector<Descriptor>& all,
                           const std::vector<std::uint32_t>& members) {
  SplitResult result;
  for (std::uint32_t m : members) {
    auto it = std::find_if(result.clusters.begin(), result.clusters.end(),
                           [&](const Cluster& c) { return c.centre == all[m]; });
    if (it == result.clusters.end()) {
      result.clusters.push_back(Cluster{all[m], {}});
      it = std::prev(result.clusters.end());
    }
    it->members.push_back(m);
  }
  return result;
}

// k-means++ seeding then Lloyd iterations with majority-vote centres (see train_vocabulary).
SplitResult split_kmeans(const std::vector<Descriptor>& all,
                         const std::vector<std::uint32_t>& members, int k, int max_iterations,
                         std::uint64_t seed) {
  const std::size_t n = members.size();
  std::vector<Descriptor> data(n);
  for (std::size_t i = 0; i < n; ++i) data[i] = all[members[i]];

  SplitMix64 rng(seed);
  std::vector<Descriptor> centres;
  centres.reserve(static_cast<std::size_t>(k));
  centres.push_back(data[rng.below(n)]);
  std::vector<std::uint32_t> min_sq(n, std::numeric_limits<std::uint32_t>::max());
  std::uint64_t total = update_min_squared_distance(data.data(), n, centres.back(), min_sq.data());
  while (static_cast<int>(centres.size()) < k && total > 0) {
    const std::uint64_t r = rng.below(total);
    std::uint64_t cumulative = 0;
    std::size_t pick = n - 1;
    for (std::size_t i = 0; i < n; ++i) {
      cumulative += min_sq[i];
      if (cumulative > r) {
        pick = i;
        break;
      }
    }
    centres.push_back(data[pick]);
    total = update_min_squared_distance(data.data(), n, centres.back(), min_sq.data());
  }
  const int kc = static_cast<int>(centres.size());

  SplitResult result;
  std::vector<std::uint32_t> label(n, std::numeric_limits<std::uint32_t>::max());
  std::vector<std::uint32_t> previous;
  std::vector<std::int32_t> counts(static_cast<std::size_t>(kc) * kDescriptorBits, 0);
  std::vector<std::int32_t> sizes(static_cast<std::size_t>(kc), 0);
  assign_nearest(data.data(), n, centres.data(), kc, label.data());
  result.iterations = 1;
  for (std::size_t i = 0; i < n; ++i) {
    add_bits(data[i], &counts[label[i] * kDescriptorBits], 1);
    ++sizes[label[i]];
  }
  while (true) {
    for (int c = 0; c < kc; ++c) {
      if (sizes[c] > 0) centres[c] = majority(&counts[c * kDescriptorBits], sizes[c]);
    }
    if (static_cast<int>(result.iterations) >= max_iterations) {
      result.hit_max_iterations = true;
      break;
    }
    previous = label;
    const std::size_t changed = assign_nearest(data.data(), n, centres.data(), kc, label.data());
    ++result.iterations;
    if (changed == 0) break;  // centres already are the majority of these same clusters
    for (std::size_t i = 0; i < n; ++i) {
      if (label[i] == previous[i]) continue;
      add_bits(data[i], &counts[previous[i] * kDescriptorBits], -1);
      add_bits(data[i], &counts[label[i] * kDescriptorBits], 1);
      --sizes[previous[i]];
      ++sizes[label[i]];
    }
  }

  std::vector<int> cluster_of_centre(static_cast<std::size_t>(kc), -1);
  for (int c = 0; c < kc; ++c) {
    if (sizes[c] == 0) continue;  // an emptied cluster is dropped
    cluster_of_centre[c] = static_cast<int>(result.clusters.size());
    result.clusters.push_back(Cluster{centres[c], {}});
    result.clusters.back().members.reserve(static_cast<std::size_t>(sizes[c]));
  }
  for (std::size_t i = 0; i < n; ++i) {
    result.clusters[static_cast<std::size_t>(cluster_of_centre[label[i]])].members.push_back(
        members[i]);
  }
  return result;
}

// Runs body(i) for i in [0, count) on up to `threads` threads (the caller is one of them). The
// first exception stops the remaining work and is rethrown here.
template <typename Body>
void run_parallel(std::size_t count, int threads, const Body& body) {
  const auto workers =
      static_cast<std::size_t>(std::max(1, std::min<int>(threads, static_cast<int>(count))));
  if (workers <= 1) {
    for (std::size_t i = 0; i < count; ++i) body(i);
    return;
  }
  std::atomic<std::size_t> next{0};
  std::atomic<bool> failed{false};
  std::exception_ptr error;
  std::mutex error_mutex;
  const auto work = [&] {
    while (!failed.load()) {
      const std::size_t i = next.fetch_add(1);
      if (i >= count) return;
      try {
        body(i);
      } catch (...) {
        const std::lock_guard lock(error_mutex);
        if (!error) error = std::current_exception();
        failed = true;
      }
    }
  };
  std::vector<std::thread> pool;
  pool.reserve(workers - 1);
  for (std::size_t t = 1; t < workers; ++t) pool.emplace_back(work);
  work();
  for (std::thread& t : pool) t.join();
  if (error) std::rethrow_exception(error);
}

}  // namespace

Vocabulary train_vocabulary(const std::vector<cv::Mat>& image_descriptors,
                            const VocabularyConfig& config, const TrainingHooks& hooks,
                            TrainingStats* stats) {
  config.validate();
  const Stopwatch watch;
  TrainingStats local_stats;

  std::vector<Descriptor> all;
  std::vector<std::size_t> image_begin;  // per image, its first index in `all`
  for (const cv::Mat& mat : image_descriptors) {
    check_descriptor_mat(mat);
    image_begin.push_back(all.size());
    for (int r = 0; r < mat.rows; ++r)
      all.push_back(descriptor_from_bytes(mat.ptr<std::uint8_t>(r)));
    if (mat.rows > 0) ++local_stats.images;
  }
  image_begin.push_back(all.size());
  if (all.empty()) {
    // The images are the input: blank or featureless pictures are bad input (exit code 2).
    throw InputError("vocabulary training: no ORB features in any of the training images");
  }
  if ((config.weighting == Weighting::kTfIdf || config.weighting == Weighting::kIdf) &&
      local_stats.images < 2) {
    // idf = log(N / n_w) is 0 for every word when N = 1: every bag of words would be empty, and
    // relocalization and loop detection would find nothing (review, stop 26).
    throw InputError(
        "vocabulary training: tf-idf and idf weighting need ORB features from at least 2 "
        "training images (with one, every word's idf log(N / n) is 0); give more images or "
        "choose tf or binary weighting");
  }
  if (all.size() >= std::numeric_limits<std::uint32_t>::max()) {
    throw Error(fmt::format("vocabulary training: too many descriptors ({})", all.size()));
  }
  local_stats.descriptors = all.size();
  const auto check_stop = [&] {
    if (hooks.stop != nullptr && hooks.stop->load()) throw Interrupted();
  };

  struct Pending {
    NodeId node = 0;
    std::vector<std::uint32_t> members;
  };
  std::vector<VocabularyNode> nodes(1);  // the root: no parent, no descriptor, no weight
  std::vector<Pending> pending(1);
  pending[0].members.resize(all.size());
  for (std::size_t i = 0; i < all.size(); ++i)
    pending[0].members[i] = static_cast<std::uint32_t>(i);

  std::mutex progress_mutex;
  for (int level = 1; level <= config.levels && !pending.empty(); ++level) {
    std::vector<SplitResult> results(pending.size());
    std::size_t done = 0;
    run_parallel(pending.size(), config.threads, [&](std::size_t i) {
      check_stop();
      const Pending& p = pending[i];
      results[i] = p.members.size() <= static_cast<std::size_t>(config.branching)
                       ? split_distinct(all, p.members)
                       : split_kmeans(all, p.members, config.branching, config.max_iterations,
                                      node_seed(config.seed, p.node));
      if (hooks.on_progress) {
        const std::lock_guard lock(progress_mutex);
        hooks.on_progress(TrainingProgress{level, ++done, pending.size()});
      }
    });
    std::vector<Pending> next;
    for (std::size_t i = 0; i < pending.size(); ++i) {
      SplitResult& r = results[i];
      local_stats.splits += 1;
      local_stats.iterations += r.iterations;
      local_stats.splits_hit_max_iterations += r.hit_max_iterations ? 1 : 0;
      for (Cluster& c : r.clusters) {
        const auto id = static_cast<NodeId>(nodes.size());
        nodes.push_back(VocabularyNode{pending[i].node, c.centre, 0.0f});
        if (level < config.levels && c.members.size() > 1 && !all_equal(all, c.members)) {
          next.push_back(Pending{id, std::move(c.members)});
        }
      }
    }
    spdlog::debug("vocabulary level {}: {} splits, {} nodes so far", level, pending.size(),
                  nodes.size());
    pending = std::move(next);
  }

  // Word weights. The IDF counts, for every word, the images with a descriptor that *descends* to
  // it (what a query will see), not the k-means membership, which can differ at the last step.
  Vocabulary unweighted =
      Vocabulary::from_nodes(config.branching, config.levels, config.weighting, nodes);
  check_stop();
  std::vector<WordId> word_of(all.size());
  const std::size_t chunk = 4096;
  run_parallel((all.size() + chunk - 1) / chunk, config.threads, [&](std::size_t c) {
    const std::size_t end = std::min(all.size(), (c + 1) * chunk);
    for (std::size_t i = c * chunk; i < end; ++i) word_of[i] = unweighted.word(all[i]);
  });
  std::vector<std::uint32_t> images_with_word(unweighted.word_count(), 0);
  std::vector<std::uint32_t> last_image(unweighted.word_count(),
                                        std::numeric_limits<std::uint32_t>::max());
  for (std::size_t img = 0; img + 1 < image_begin.size(); ++img) {
    for (std::size_t i = image_begin[img]; i < image_begin[img + 1]; ++i) {
      const WordId w = word_of[i];
      if (last_image[w] != img) {
        last_image[w] = static_cast<std::uint32_t>(img);
        ++images_with_word[w];
      }
    }
  }
  const bool use_idf = config.weighting == Weighting::kTfIdf || config.weighting == Weighting::kIdf;
  const double n_images = static_cast<double>(local_stats.images);
  for (WordId w = 0; w < unweighted.word_count(); ++w) {
    const double n_w = std::max<double>(1.0, images_with_word[w]);
    nodes[unweighted.node_of_word(w)].weight =
        use_idf ? static_cast<float>(std::log(n_images / n_w)) : 1.0f;
  }
  Vocabulary vocabulary =
      Vocabulary::from_nodes(config.branching, config.levels, config.weighting, std::move(nodes));

  local_stats.nodes = vocabulary.node_count();
  local_stats.words = vocabulary.word_count();
  local_stats.seconds = watch.elapsed_ms() / 1000.0;
  if (stats != nullptr) *stats = local_stats;
  return vocabulary;
}

}  // namespace ddl::vocabulary
