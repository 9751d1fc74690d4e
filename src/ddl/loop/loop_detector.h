#pragma once
// Loop candidate detection (ORB-SLAM2 LoopClosing::DetectLoop and
// KeyFrameDatabase::DetectLoopCandidates; ORB-SLAM T-RO 2015 section VII-A):
//   1. s_min = the lowest BoW score between the keyframe and its covisible keyframes;
//   2. database query excluding the keyframe and every keyframe it shares a map point with
//      (KeyFrame::connected_keyframes, not only the covisibles of weight >= 15); keep keyframes
//      sharing more than min_common_words_ratio of the best candidate's shared words and scoring
//      >= s_min;
//   3. group each with its best covisibles (accumulated score), keep the best keyframe of every
//      group scoring more than min_group_score_ratio of the best group;
//   4. a candidate is consistent when its group (itself and every keyframe it shares a point
//      with) continues a group that was already consistent for the previous
//      consistency_threshold keyframes (0: at once; the geometric verification still decides).
// The candidates of step 3 that are not consistent yet are reported too: the loop closer may
// accept one whose loop is confirmed in the keyframe's covisibles instead (loop_closer.h).
// Thread-safety: one instance belongs to loop closing; detect() from one thread at a time.

#include <cstddef>
#include <memory>
#include <set>
#include <utility>
#include <vector>

#include "ddl/loop/loop_closer_config.h"
#include "ddl/map/keyframe.h"
#include "ddl/map/map.h"
#include "ddl/vocabulary/bow_database.h"

namespace ddl::loop {

class LoopDetector {
 public:
  LoopDetector(const LoopDetectionConfig& config, std::shared_ptr<map::Map> map,
               std::shared_ptr<vocabulary::BowDatabase> database);

  struct Detection {
    std::vector<map::KeyFramePtr> consistent;  ///< consistent for enough keyframes (ascending id)
    std::vector<map::KeyFramePtr> pending;     ///< the other candidates (ascending id)
  };

  /// The candidates of `keyframe`, split by the consistency test. The keyframe needs its BoW;
  /// keyframes closer than min_keyframes_between_loops to the last loop (or to the first
  /// keyframe) give none.
  Detection detect(const map::KeyFramePtr& keyframe);

  /// Candidates before the consistency test (steps 1 to 3), ascending id. Exposed for tests.
  std::vector<map::KeyFramePtr> candidates(const map::KeyFramePtr& keyframe) const;

  /// Called after a loop was closed at `keyframe_id`: detection pauses for the next
  /// min_keyframes_between_loops keyframes.
  void set_last_loop_keyframe(map::KeyFrameId keyframe_id) { last_loop_keyframe_ = keyframe_id; }

  /// The map was cleared: forgets the consistent groups; detection restarts with the keyframes
  /// from `first_keyframe` on.
  void reset(map::KeyFrameId first_keyframe) {
    consistent_groups_.clear();
    last_loop_keyframe_ = first_keyframe;
  }

 private:
  using Group = std::set<map::KeyFrameId>;

  LoopDetectionConfig config_;
  std::shared_ptr<map::Map> map_;
  std::shared_ptr<vocabulary::BowDatabase> database_;
  map::KeyFrameId last_loop_keyframe_ = 0;
  std::vector<std::pair<Group, int>> consistent_groups_;  // (group, consistency count)
};

}  // namespace ddl::loop
