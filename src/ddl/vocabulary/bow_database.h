#pragma once
// Inverted index over BoW vectors (DBoW2's database, ORB-SLAM2's KeyFrameDatabase without the
// map): for every word, the entries whose vector contains it. A query visits only the entries that
// share a word with it and returns them ranked by L1 score, with the number of shared words, for
// loop-closure and relocalization candidate search.
//
// Entries are opaque ids (keyframe ids); the database knows nothing of keyframes or the map.
// Thread-safe: every method may be called from any thread; add/erase/clear take an internal
// exclusive lock, queries a shared one (queries run concurrently with each other).

#include <cstddef>
#include <cstdint>
#include <shared_mutex>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "ddl/vocabulary/bow_vector.h"

namespace ddl::vocabulary {

using EntryId = std::uint64_t;

struct QueryResult {
  EntryId entry_id = 0;
  double score = 0.0;              // L1 score against the query, in (0, 1]
  std::uint32_t shared_words = 0;  // words present in both vectors
  friend bool operator==(const QueryResult&, const QueryResult&) = default;
};

class BowDatabase {
 public:
  BowDatabase() = default;
  BowDatabase(const BowDatabase&) = delete;
  BowDatabase& operator=(const BowDatabase&) = delete;

  /// Adds (or replaces) an entry. The vector is stored L1-normalised.
  /// Adds (or replaces) an entry; an id below the floor of the last clear() is refused (false).
  bool add(EntryId entry_id, const BowVector& bow);
  /// Removes an entry; returns false when it was not present.
  bool erase(EntryId entry_id);
  /// Removes every entry; from then on ids below `floor` are refused by add() (the keyframes of
  /// a map that was reset, still in the hands of another stage).
  void clear(EntryId floor = 0);
  std::size_t size() const;
  bool contains(EntryId entry_id) const;

  /// The entries sharing at least `min_shared_words` (>= 1) words with `bow`, not in `exclude`,
  /// whose L1 score is >= min_score; best score first (ties: more shared words, then lower id),
  /// at most max_results of them (0 = all). Scores equal l1_score(bow, entry vector) up to
  /// rounding.
  std::vector<QueryResult> query(const BowVector& bow, std::size_t max_results,
                                 double min_score = 0.0,
                                 const std::unordered_set<EntryId>& exclude = {},
                                 std::uint32_t min_shared_words = 1) const;

 private:
  struct Posting {
    EntryId entry_id;
    double weight;  // the entry's normalised weight for this word
  };

  mutable std::shared_mutex mutex_;
  std::unordered_map<WordId, std::vector<Posting>> postings_;
  std::unordered_map<EntryId, BowVector> entries_;  // normalised vectors, for erase()
  EntryId floor_ = 0;                               // see clear()
};

}  // namespace ddl::vocabulary
