#pragma once
// Follows the rigid corrections that loop closing and global BA apply to the keyframes around
// the camera, for data the tracking thread keeps in the world frame outside the map (the dynamic
// memory's remembered points and static views). ORB-SLAM2 and this tracker keep the camera pose
// relative to its reference keyframe for the same reason; data computed at a tracked pose is
// anchored to that pose's reference keyframe here.
//
// A loop correction moves the current keyframe's covisible neighbourhood rigidly with the
// current keyframe (loop::LoopCorrector), and a global-BA merge moves every keyframe; both
// then call Map::notify_big_change(). After such a change, correction() gives the motion of the
// anchor keyframe, T_w_new_w_old, which maps a point kept in the old world frame to the new one.
// Small local-BA refinements are not followed (they are not announced, and the data kept here
// lives for about two seconds).
//
// Thread-safety: one instance per tracking thread; the keyframe poses are read under
// Map::read_consistent.

#include <memory>
#include <optional>

#include "ddl/core/se3.h"
#include "ddl/map/keyframe.h"
#include "ddl/map/map.h"

namespace ddl::pipeline {

class MapCorrectionFollower {
 public:
  explicit MapCorrectionFollower(std::shared_ptr<const map::Map> map) : map_(std::move(map)) {}

  /// Anchors the data computed at a pose tracked against `reference` (non-null) to that
  /// keyframe's pose now.
  void anchor(const map::KeyFramePtr& reference);

  /// When the map announced a big change since the anchor was taken: the rigid motion of the
  /// anchor keyframe, T_w_new_w_old (identity when it did not move), and the anchor is re-taken
  /// at the new pose. Otherwise, or without an anchor, nullopt.
  std::optional<SE3> correction();

  /// Drops the anchor (map reset).
  void reset() { anchor_ = nullptr; }

 private:
  std::shared_ptr<const map::Map> map_;
  map::KeyFramePtr anchor_;
  SE3 T_w_anchor_;           // the anchor's pose when last read (tracking::resolved_T_w_c)
  int seen_big_change_ = 0;  // Map::big_change_index when last read
};

}  // namespace ddl::pipeline
