#include "ddl/vocabulary/bow_vector.h"

#include <algorithm>
#include <cmath>

namespace ddl::vocabulary {

BowVector BowVector::from_entries(std::vector<BowEntry> entries) {
  std::sort(entries.begin(), entries.end(),
            [](const BowEntry& a, const BowEntry& b) { return a.word_id < b.word_id; });
  BowVector out;
  out.entries_.reserve(entries.size());
  for (const BowEntry& e : entries) {
    if (!out.entries_.empty() && out.entries_.back().word_id == e.word_id) {
      out.entries_.back().weight += e.weight;
    } else {
      out.entries_.push_back(e);
    }
  }
  std::erase_if(out.entries_, [](const BowEntry& e) { return !(e.weight > 0.0); });
  return out;
}

double BowVector::weight(WordId word_id) const {
  const auto it = std::lower_bound(entries_.begin(), entries_.end(), word_id,
                                   [](const BowEntry& e, WordId id) { return e.word_id < id; });
  return (it != entries_.end() && it->word_id == word_id) ? it->weight : 0.0;
}

double BowVector::l1_norm() const {
  double sum = 0.0;
  for (const BowEntry& e : entries_) sum += e.weight;
  return sum;
}

void BowVector::normalize_l1() {
  const double norm = l1_norm();
  if (!(norm > 0.0)) return;
  for (BowEntry& e : entries_) e.weight /= norm;
}

double l1_score(const BowVector& a, const BowVector& b) {
  const double norm_a = a.l1_norm();
  const double norm_b = b.l1_norm();
  if (!(norm_a > 0.0) || !(norm_b > 0.0)) return 0.0;
  // Merge the two sorted sparse vectors, summing |a_i/|a| - b_i/|b|| over the union of words.
  double distance = 0.0;
  auto ia = a.begin();
  auto ib = b.begin();
  while (ia != a.end() && ib != b.end()) {
    if (ia->word_id < ib->word_id) {
      distance += ia->weight / norm_a;
      ++ia;
    } else if (ib->word_id < ia->word_id) {
      distance += ib->weight / norm_b;
      ++ib;
    } else {
      distance += std::abs(ia->weight / norm_a - ib->weight / norm_b);
      ++ia;
      ++ib;
    }
  }
  for (; ia != a.end(); ++ia) distance += ia->weight / norm_a;
  for (; ib != b.end(); ++ib) distance += ib->weight / norm_b;
  return std::clamp(1.0 - 0.5 * distance, 0.0, 1.0);
}

FeatureVector FeatureVector::from_pairs(std::vector<std::pair<NodeId, std::uint32_t>> pairs) {
  std::sort(pairs.begin(), pairs.end());
  FeatureVector out;
  for (const auto& [node_id, feature] : pairs) {
    if (out.nodes_.empty() || out.nodes_.back().node_id != node_id) {
      out.nodes_.push_back(FeatureNode{node_id, {}});
    }
    out.nodes_.back().feature_indices.push_back(feature);
  }
  return out;
}

const std::vector<std::uint32_t>* FeatureVector::find(NodeId node_id) const {
  const auto it = std::lower_bound(nodes_.begin(), nodes_.end(), node_id,
                                   [](const FeatureNode& n, NodeId id) { return n.node_id < id; });
  return (it != nodes_.end() && it->node_id == node_id) ? &it->feature_indices : nullptr;
}

std::size_t FeatureVector::feature_count() const {
  std::size_t n = 0;
  for (const FeatureNode& node : nodes_) n += node.feature_indices.size();
  return n;
}

}  // namespace ddl::vocabulary
