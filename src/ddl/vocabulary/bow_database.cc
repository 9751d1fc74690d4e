#include "ddl/vocabulary/bow_database.h"

#include <algorithm>
#include <mutex>

namespace ddl::vocabulary {
namespace {

BowVector normalised(const BowVector& bow) {
  BowVector out = bow;
  out.normalize_l1();
  return out;
}

}  // namespace

bool BowDatabase::add(EntryId entry_id, const BowVector& bow) {
  BowVector stored = normalised(bow);
  const std::unique_lock lock(mutex_);
  if (entry_id < floor_) return false;
  if (const auto it = entries_.find(entry_id); it != entries_.end()) {
    for (const BowEntry& e : it->second) {
      std::vector<Posting>& list = postings_[e.word_id];
      std::erase_if(list, [&](const Posting& p) { return p.entry_id == entry_id; });
      if (list.empty()) postings_.erase(e.word_id);
    }
  }
  for (const BowEntry& e : stored) postings_[e.word_id].push_back(Posting{entry_id, e.weight});
  entries_[entry_id] = std::move(stored);
  return true;
}

bool BowDatabase::erase(EntryId entry_id) {
  const std::unique_lock lock(mutex_);
  const auto it = entries_.find(entry_id);
  if (it == entries_.end()) return false;
  for (const BowEntry& e : it->second) {
    const auto list_it = postings_.find(e.word_id);
    if (list_it == postings_.end()) continue;
    std::erase_if(list_it->second, [&](const Posting& p) { return p.entry_id == entry_id; });
    if (list_it->second.empty()) postings_.erase(list_it);
  }
  entries_.erase(it);
  return true;
}

void BowDatabase::clear(EntryId floor) {
  const std::unique_lock lock(mutex_);
  postings_.clear();
  entries_.clear();
  floor_ = floor;
}

std::size_t BowDatabase::size() const {
  const std::shared_lock lock(mutex_);
  return entries_.size();
}

bool BowDatabase::contains(EntryId entry_id) const {
  const std::shared_lock lock(mutex_);
  return entries_.contains(entry_id);
}

std::vector<QueryResult> BowDatabase::query(const BowVector& bow, std::size_t max_results,
                                            double min_score,
                                            const std::unordered_set<EntryId>& exclude,
                                            std::uint32_t min_shared_words) const {
  const BowVector q = normalised(bow);
  // For L1-normalised non-negative vectors, 1 - 0.5 * |a - b|_1 = sum over shared words of
  // min(a_w, b_w): only shared words contribute, so the inverted index gives the exact score.
  struct Accumulator {
    double score = 0.0;
    std::uint32_t shared = 0;
  };
  std::unordered_map<EntryId, Accumulator> acc;
  {
    const std::shared_lock lock(mutex_);
    for (const BowEntry& e : q) {
      const auto it = postings_.find(e.word_id);
      if (it == postings_.end()) continue;
      for (const Posting& p : it->second) {
        if (exclude.contains(p.entry_id)) continue;
        Accumulator& a = acc[p.entry_id];
        a.score += std::min(e.weight, p.weight);
        ++a.shared;
      }
    }
  }
  std::vector<QueryResult> results;
  results.reserve(acc.size());
  const std::uint32_t min_shared = std::max<std::uint32_t>(1, min_shared_words);
  for (const auto& [id, a] : acc) {
    const double score = std::clamp(a.score, 0.0, 1.0);
    if (a.shared >= min_shared && score >= min_score) {
      results.push_back(QueryResult{id, score, a.shared});
    }
  }
  std::sort(results.begin(), results.end(), [](const QueryResult& a, const QueryResult& b) {
    if (a.score != b.score) return a.score > b.score;
    if (a.shared_words != b.shared_words) return a.shared_words > b.shared_words;
    return a.entry_id < b.entry_id;
  });
  if (max_results > 0 && results.size() > max_results) results.resize(max_results);
  return results;
}

}  // namespace ddl::vocabulary
