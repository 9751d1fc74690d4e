#pragma once
// Sparse bag-of-words vectors (word id -> weight), the direct index of an image (vocabulary node ->
// the image's features under it), and the L1 similarity score of DBoW2 / Nister-Stewenius.
// Plain value types: safe to share between threads once built.

#include <cstddef>
#include <cstdint>
#include <utility>
#include <vector>

namespace ddl::vocabulary {

/// A word is a leaf of the vocabulary tree; word ids are 0..word_count()-1.
using WordId = std::uint32_t;
/// A node of the vocabulary tree; node 0 is the root, ids are 0..node_count()-1.
using NodeId = std::uint32_t;

struct BowEntry {
  WordId word_id = 0;
  double weight = 0.0;
  friend bool operator==(const BowEntry&, const BowEntry&) = default;
};

/// Sparse vector over words: entries sorted by word id, each id once, weights > 0. Vectors made by
/// Vocabulary::transform are L1-normalised (weights sum to 1).
class BowVector {
 public:
  BowVector() = default;
  /// From entries in any order: repeated ids are summed, entries with weight <= 0 dropped.
  static BowVector from_entries(std::vector<BowEntry> entries);

  const std::vector<BowEntry>& entries() const { return entries_; }
  std::vector<BowEntry>::const_iterator begin() const { return entries_.begin(); }
  std::vector<BowEntry>::const_iterator end() const { return entries_.end(); }
  std::size_t size() const { return entries_.size(); }
  bool empty() const { return entries_.empty(); }
  /// The weight of a word, 0 when absent (binary search).
  double weight(WordId word_id) const;
  /// Sum of the weights.
  double l1_norm() const;
  /// Scales the weights to sum to 1 (no-op for an empty vector).
  void normalize_l1();

  friend bool operator==(const BowVector&, const BowVector&) = default;

 private:
  std::vector<BowEntry> entries_;
};

/// L1 score of DBoW2 (Nister & Stewenius 2006): s = 1 - 0.5 * | a/|a| - b/|b| |_1, in [0, 1];
/// 1 for identical word histograms, 0 for no shared word or an empty vector.
double l1_score(const BowVector& a, const BowVector& b);

/// The features of one image under one vocabulary node (DBoW2's FeatureVector entry).
struct FeatureNode {
  NodeId node_id = 0;
  std::vector<std::uint32_t> feature_indices;  // rows of the image's descriptor matrix, ascending
  friend bool operator==(const FeatureNode&, const FeatureNode&) = default;
};

/// Direct index of an image: its features grouped by the vocabulary node they pass through at a
/// chosen depth, sorted by node id. Matching two images compares only features that share a node
/// (walk two FeatureVectors in step, as ORB-SLAM2's SearchByBoW does).
class FeatureVector {
 public:
  FeatureVector() = default;
  /// From (node id, feature index) pairs in any order.
  static FeatureVector from_pairs(std::vector<std::pair<NodeId, std::uint32_t>> pairs);

  const std::vector<FeatureNode>& nodes() const { return nodes_; }
  std::vector<FeatureNode>::const_iterator begin() const { return nodes_.begin(); }
  std::vector<FeatureNode>::const_iterator end() const { return nodes_.end(); }
  std::size_t size() const { return nodes_.size(); }
  bool empty() const { return nodes_.empty(); }
  /// The features under `node_id`, or nullptr when none (binary search).
  const std::vector<std::uint32_t>* find(NodeId node_id) const;
  /// Total number of features.
  std::size_t feature_count() const;

  friend bool operator==(const FeatureVector&, const FeatureVector&) = default;

 private:
  std::vector<FeatureNode> nodes_;
};

/// Walks two FeatureVectors in step and calls visit(features_a, features_b) for every node both
/// have, in ascending node order (the candidate pairs of SearchByBoW-style matching).
template <class Visit>
void for_each_shared_node(const FeatureVector& a, const FeatureVector& b, Visit&& visit) {
  auto it_a = a.begin();
  auto it_b = b.begin();
  while (it_a != a.end() && it_b != b.end()) {
    if (it_a->node_id < it_b->node_id) {
      ++it_a;
    } else if (it_b->node_id < it_a->node_id) {
      ++it_b;
    } else {
      visit(it_a->feature_indices, it_b->feature_indices);
      ++it_a;
      ++it_b;
    }
  }
}

}  // namespace ddl::vocabulary
