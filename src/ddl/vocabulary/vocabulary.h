#pragma once
// A binary bag-of-words vocabulary: a tree of binary descriptors built by hierarchical k-means
// (Nister & Stewenius, CVPR 2006; binary form of Galvez-Lopez & Tardos, T-RO 2012). A descriptor
// descends from the root to the nearest child (Hamming distance) at every level; the leaf it
// reaches is its word. Words carry an IDF weight learnt from the training images.
//
// Immutable after construction: every const method may be called from any number of threads at
// once. Load it once and share it (e.g. std::shared_ptr<const Vocabulary>).

#include <cstddef>
#include <cstdint>
#include <opencv2/core.hpp>
#include <span>
#include <string>
#include <vector>

#include "ddl/vocabulary/bow_vector.h"
#include "ddl/vocabulary/descriptor.h"
#include "ddl/vocabulary/vocabulary_config.h"

namespace ddl::vocabulary {

/// Parent id of the root.
inline constexpr NodeId kNoNode = 0xFFFFFFFFu;

/// One node as stored in a vocabulary file and given to Vocabulary::from_nodes.
struct VocabularyNode {
  NodeId parent = kNoNode;  // kNoNode for the root (node 0); otherwise an id lower than this one's
  Descriptor descriptor{};  // cluster centre (per-bit majority of its training descriptors)
  float weight = 0.0f;      // words (leaves): IDF (tf-idf, idf) or 1 (tf, binary); others 0
  friend bool operator==(const VocabularyNode&, const VocabularyNode&) = default;
};

/// Where one descriptor lands in the tree.
struct WordLookup {
  WordId word_id = 0;   // the leaf reached
  double weight = 0.0;  // the word's weight (IDF for tf-idf)
  NodeId node_id = 0;   // the ancestor `levels_up` levels above the deepest level (direct index)
};

class Vocabulary {
 public:
  /// An empty vocabulary (no words); transform() of it gives empty vectors.
  Vocabulary() = default;

  /// Builds a vocabulary from its nodes (node 0 the root, each parent id lower than its child's,
  /// siblings with consecutive ids, as breadth-first order gives). Leaves become words, numbered in
  /// node-id order. Throws ddl::Error describing the first structural problem (a parent out of
  /// order, siblings not consecutive, more than `branching` children, a node deeper than `levels`,
  /// a negative or non-finite weight, no words).
  static Vocabulary from_nodes(int branching, int levels, Weighting weighting,
                               std::vector<VocabularyNode> nodes);

  /// Reads a vocabulary file (format in docs/vocabulary.md). Throws ddl::InputError naming the
  /// file when it is missing, has a wrong magic or version, is truncated, fails its checksum or
  /// holds an invalid tree.
  static Vocabulary load(const std::string& path);
  /// Writes the vocabulary file; load(save(v)) == v exactly. Throws ddl::Error naming the file
  /// when it cannot be written.
  void save(const std::string& path) const;

  /// Identifies the descriptor the vocabulary was trained for (0 = not recorded). `vocab train`
  /// stores descriptor_fingerprint() of the ORB extractor's BRIEF pattern: a vocabulary is useless
  /// with descriptors of another pattern, so the loader of a vocabulary should compare it.
  std::uint64_t descriptor_tag() const { return descriptor_tag_; }
  /// Sets the tag (before the vocabulary is shared between threads).
  void set_descriptor_tag(std::uint64_t tag) { descriptor_tag_ = tag; }

  bool empty() const { return word_node_.empty(); }
  int branching() const { return branching_; }
  int levels() const { return levels_; }
  Weighting weighting() const { return weighting_; }
  std::size_t node_count() const { return parents_.size(); }
  std::size_t word_count() const { return word_node_.size(); }

  // --- Tree access ---------------------------------------------------------------------------
  NodeId parent(NodeId node) const { return parents_[node]; }
  /// Depth below the root (root 0, words at 1..levels()).
  int depth(NodeId node) const { return depths_[node]; }
  /// Children have consecutive ids first_child(n) .. first_child(n) + child_count(n) - 1.
  NodeId first_child(NodeId node) const { return first_child_[node]; }
  int child_count(NodeId node) const { return child_counts_[node]; }
  bool is_word(NodeId node) const { return child_counts_[node] == 0; }
  /// The word of a leaf node (precondition: is_word(node)).
  WordId word_of_node(NodeId node) const { return node_words_[node]; }
  NodeId node_of_word(WordId word) const { return word_node_[word]; }
  const Descriptor& node_descriptor(NodeId node) const { return descriptors_[node]; }
  double word_weight(WordId word) const { return weights_[word_node_[word]]; }
  /// The nodes in storage form (what save() writes).
  std::vector<VocabularyNode> nodes() const;

  // --- Descriptor to word ---------------------------------------------------------------------
  /// Descends the tree with `descriptor`. node_id is the ancestor of the word at depth
  /// max(0, levels() - levels_up), or the word itself when the word is shallower (levels_up = 0:
  /// the word's node). Precondition: !empty().
  WordLookup lookup(const Descriptor& descriptor, int levels_up = 0) const;
  /// The word of one descriptor. Precondition: !empty().
  WordId word(const Descriptor& descriptor) const { return lookup(descriptor).word_id; }

  /// BoW vector of an image's descriptors (N x 32 CV_8U), weighted by weighting() and
  /// L1-normalised. Words of weight 0 (seen in every training image) are left out, as in DBoW2.
  BowVector transform(const cv::Mat& descriptors) const;
  BowVector transform(std::span<const Descriptor> descriptors) const;
  /// BoW vector plus direct index: every feature i (row i) is listed under its node at
  /// `levels_up` levels above the deepest level, including features whose word has weight 0.
  /// ORB-SLAM2 uses 4 with levels() = 6, i.e. nodes at depth 2; levels() - 2 gives that depth
  /// for any vocabulary (3 for the default L = 5 one).
  void transform(const cv::Mat& descriptors, int levels_up, BowVector& bow,
                 FeatureVector& features) const;
  void transform(std::span<const Descriptor> descriptors, int levels_up, BowVector& bow,
                 FeatureVector& features) const;

  /// L1 score of two BoW vectors (l1_score), in [0, 1].
  static double score(const BowVector& a, const BowVector& b) { return l1_score(a, b); }

  friend bool operator==(const Vocabulary& a, const Vocabulary& b);

 private:
  BowVector make_bow(std::vector<WordId> words) const;
  /// Validates parents_/weights_ and derives the index arrays (from_nodes and load).
  void build_index();

  int branching_ = 0;
  int levels_ = 0;
  Weighting weighting_ = Weighting::kTfIdf;
  std::uint64_t descriptor_tag_ = 0;
  std::vector<NodeId> parents_;
  std::vector<Descriptor> descriptors_;
  std::vector<float> weights_;
  std::vector<std::uint8_t> depths_;
  std::vector<NodeId> first_child_;         // siblings have consecutive ids (checked)
  std::vector<std::uint8_t> child_counts_;  // 0 for words
  std::vector<WordId> node_words_;          // word id of a leaf; kNoNode for inner nodes
  std::vector<NodeId> word_node_;
};

/// 64-bit FNV-1a hash of `size` bytes, e.g. of the BRIEF pattern (the descriptor tag).
std::uint64_t descriptor_fingerprint(const void* data, std::size_t size);

}  // namespace ddl::vocabulary
