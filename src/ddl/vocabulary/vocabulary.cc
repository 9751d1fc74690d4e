#include "ddl/vocabulary/vocabulary.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "ddl/core/error.h"

namespace ddl::vocabulary {

Vocabulary Vocabulary::from_nodes(int branching, int levels, Weighting weighting,
                                  std::vector<VocabularyNode> nodes) {
  Vocabulary v;
  v.branching_ = branching;
  v.levels_ = levels;
  v.weighting_ = weighting;
  v.parents_.resize(nodes.size());
  v.descriptors_.resize(nodes.size());
  v.weights_.resize(nodes.size());
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    v.parents_[i] = nodes[i].parent;
    v.descriptors_[i] = nodes[i].descriptor;
    v.weights_[i] = nodes[i].weight;
  }
  v.build_index();
  return v;
}

void Vocabulary::build_index() {
  VocabularyConfig config;
  config.branching = branching_;
  config.levels = levels_;
  config.weighting = weighting_;
  config.validate();
  const std::size_t n = parents_.size();
  if (n == 0) throw Error("vocabulary has no nodes");
  if (n >= kNoNode) throw Error(fmt::format("vocabulary has too many nodes ({})", n));
  if (parents_[0] != kNoNode) {
    throw Error(fmt::format("node 0 (the root) has parent {}, expected none", parents_[0]));
  }
  depths_.assign(n, 0);
  first_child_.assign(n, 0);
  child_counts_.assign(n, 0);
  for (std::size_t i = 0; i < n; ++i) {
    const float weight = weights_[i];
    if (!std::isfinite(weight) || weight < 0.0f) {
      throw Error(fmt::format("node {}: weight {} is not a finite value >= 0", i, weight));
    }
    if (i == 0) continue;
    const auto id = static_cast<NodeId>(i);
    const NodeId p = parents_[i];
    if (p >= id) throw Error(fmt::format("node {}: parent {} is not a lower node id", i, p));
    if (child_counts_[p] == 0) {
      first_child_[p] = id;
    } else if (first_child_[p] + child_counts_[p] != id) {
      throw Error(
          fmt::format("node {}: siblings under parent {} do not have consecutive ids", i, p));
    }
    if (child_counts_[p] >= branching_) {
      throw Error(fmt::format("node {}: parent {} has more than {} children", i, p, branching_));
    }
    ++child_counts_[p];
    depths_[i] = static_cast<std::uint8_t>(depths_[p] + 1);
    if (depths_[i] > levels_) {
      throw Error(fmt::format("node {}: depth {} exceeds the {} levels", i, depths_[i], levels_));
    }
  }
  node_words_.assign(n, kNoNode);
  word_node_.clear();
  word_node_.reserve(static_cast<std::size_t>(
      std::count(child_counts_.begin() + 1, child_counts_.end(), std::uint8_t{0})));
  for (std::size_t i = 1; i < n; ++i) {
    if (child_counts_[i] == 0) {
      node_words_[i] = static_cast<WordId>(word_node_.size());
      word_node_.push_back(static_cast<NodeId>(i));
    }
  }
  if (word_node_.empty()) throw Error("vocabulary has no words (the root has no children)");
}

std::vector<VocabularyNode> Vocabulary::nodes() const {
  std::vector<VocabularyNode> out(node_count());
  for (std::size_t i = 0; i < out.size(); ++i) {
    out[i] = VocabularyNode{parents_[i], descriptors_[i], weights_[i]};
  }
  return out;
}

WordLookup Vocabulary::lookup(const Descriptor& descriptor, int levels_up) const {
  if (empty()) throw Error("descriptor lookup in an empty vocabulary");
  const int target_depth = std::max(0, levels_ - std::max(0, levels_up));
  NodeId node = 0;
  NodeId at_depth = 0;
  int depth = 0;
  while (child_counts_[node] > 0) {
    const NodeId first = first_child_[node];
    node = first + static_cast<NodeId>(nearest_descriptor(descriptor, &descriptors_[first],
                                                          child_counts_[node], nullptr));
    ++depth;
    if (depth <= target_depth) at_depth = node;
  }
  return WordLookup{node_words_[node], static_cast<double>(weights_[node]), at_depth};
}

BowVector Vocabulary::make_bow(std::vector<WordId> words) const {
  std::sort(words.begin(), words.end());
  const bool accumulate = weighting_ == Weighting::kTfIdf || weighting_ == Weighting::kTf;
  std::vector<BowEntry> entries;
  for (std::size_t i = 0; i < words.size();) {
    std::size_t j = i;
    while (j < words.size() && words[j] == words[i]) ++j;
    const double w = weights_[word_node_[words[i]]];
    if (w > 0.0) {
      entries.push_back(BowEntry{words[i], accumulate ? w * static_cast<double>(j - i) : w});
    }
    i = j;
  }
  BowVector bow = BowVector::from_entries(std::move(entries));
  bow.normalize_l1();
  return bow;
}

BowVector Vocabulary::transform(std::span<const Descriptor> descriptors) const {
  if (empty()) return {};
  std::vector<WordId> words;
  words.reserve(descriptors.size());
  for (const Descriptor& d : descriptors) words.push_back(lookup(d).word_id);
  return make_bow(std::move(words));
}

BowVector Vocabulary::transform(const cv::Mat& descriptors) const {
  return transform(descriptors_from_mat(descriptors));
}

void Vocabulary::transform(std::span<const Descriptor> descriptors, int levels_up, BowVector& bow,
                           FeatureVector& features) const {
  bow = {};
  features = {};
  if (empty()) return;
  std::vector<WordId> words;
  words.reserve(descriptors.size());
  std::vector<std::pair<NodeId, std::uint32_t>> pairs;
  pairs.reserve(descriptors.size());
  for (std::size_t i = 0; i < descriptors.size(); ++i) {
    const WordLookup hit = lookup(descriptors[i], levels_up);
    words.push_back(hit.word_id);
    pairs.emplace_back(hit.node_id, static_cast<std::uint32_t>(i));
  }
  bow = make_bow(std::move(words));
  features = FeatureVector::from_pairs(std::move(pairs));
}

void Vocabulary::transform(const cv::Mat& descriptors, int levels_up, BowVector& bow,
                           FeatureVector& features) const {
  transform(descriptors_from_mat(descriptors), levels_up, bow, features);
}

bool operator==(const Vocabulary& a, const Vocabulary& b) {
  // Everything else is derived from these fields in from_nodes.
  return a.branching_ == b.branching_ && a.levels_ == b.levels_ && a.weighting_ == b.weighting_ &&
         a.descriptor_tag_ == b.descriptor_tag_ && a.parents_ == b.parents_ &&
         a.descriptors_ == b.descriptors_ && a.weights_ == b.weights_;
}

std::uint64_t descriptor_fingerprint(const void* data, std::size_t size) {
  std::uint64_t h = 0xCBF29CE484222325ull;
  const auto* bytes = static_cast<const unsigned char*>(data);
  for (std::size_t i = 0; i < size; ++i) {
    h ^= bytes[i];
    h *= 0x100000001B3ull;
  }
  return h;
}

}  // namespace ddl::vocabulary
