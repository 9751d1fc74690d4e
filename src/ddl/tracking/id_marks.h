#pragma once
// Per-round marks on dense ids (keyframe or map point ids come from per-map counters, so they are
// small and dense): "was this id already visited in this round?" without touching the shared
// entities (ARCHITECTURE.md section 3: scratch state lives in the algorithm) and without
// allocating once the table has grown to the largest id. Not thread-safe; owned by one algorithm.

#include <cstdint>
#include <vector>

namespace ddl::tracking {

class IdMarks {
 public:
  /// Starts a new round: every id becomes unmarked (O(1)).
  void next_round() {
    if (++round_ == 0) {  // wrapped: clear explicitly once every 2^32 rounds
      std::fill(stamps_.begin(), stamps_.end(), 0u);
      round_ = 1;
    }
  }
  /// Marks `id`; returns true if it was not marked in this round yet.
  bool mark(std::uint64_t id) {
    if (id >= stamps_.size()) stamps_.resize(grown_size(id), 0u);
    if (stamps_[id] == round_) return false;
    stamps_[id] = round_;
    return true;
  }
  bool is_marked(std::uint64_t id) const { return id < stamps_.size() && stamps_[id] == round_; }

 private:
  static std::size_t grown_size(std::uint64_t id) {
    return static_cast<std::size_t>(id + 1 + id / 2 + 1024);
  }
  std::vector<std::uint32_t> stamps_;
  std::uint32_t round_ = 1;
};

}  // namespace ddl::tracking
