#pragma once
// Follows the rigid corrections that loop closing and global BA apply to the keyframes around
// the camera, for data the tracking thread keeps in the world frame outside the map (the dynamic
// memory's remembered points and static views). ORB-SLAM2 and this tracker keep the camera pose
// relative to its reference keyframe for the same reason; data computed at a tracked pose is
// anchored to that pose's reference keyframe here.
//
// A loop correction moves the current keyframe's covisible neighbourhood rigidly with the
// current keyframe (loop::LoopCorrector), and a global-BA merge moves every keyframe; both
// write through Map::apply_frame_change(), which counts them under the map's update lock. After
// such a change, correction() gives the motion of the anchor keyframe, T_w_new_w_old, which maps
// a point kept in the old world frame to the new one. (Map::big_change_index, which the dense
// map follows, is announced only after a whole correction: a frame tracked in between would be
// anchored in the new frame to the old index, and half the motion lost; review, stop 25.)
// Small local-BA refinements are not followed (they are not announced, and the data kept here
// lives for about two seconds).
//
// Thread-safety: one instance per tracking thread; the keyframe poses are read under
// Map::read_consistent.

#include <cstdint>
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
  /// keyframe's pose now, provided the world frame is still the one of the tracked pose:
  /// Map::frame_change_count() equals `frame_changes_at_tracking`. Otherwise nothing changes and
  /// false is returned (the caller then keeps no data at that pose).
  bool anchor(const map::KeyFramePtr& reference, std::uint64_t frame_changes_at_tracking);

  /// When the world frame changed since the anchor was taken: the rigid motion of the
  /// anchor keyframe, T_w_new_w_old (identity when it did not move), and the anchor is re-taken
  /// at the new pose. Otherwise, or without an anchor, nullopt.
  std::optional<SE3> correction();

  /// Drops the anchor (map reset).
  void reset() { anchor_ = nullptr; }

 private:
  std::shared_ptr<const map::Map> map_;
  map::KeyFramePtr anchor_;
  SE3 T_w_anchor_;  // the anchor's pose when last read (tracking::resolved_T_w_c)
  std::uint64_t seen_frame_changes_ = 0;  // Map::frame_change_count when last read
};

}  // namespace ddl::pipeline
