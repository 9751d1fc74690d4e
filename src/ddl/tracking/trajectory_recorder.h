#pragma once
// Camera trajectory bookkeeping (ORB-SLAM2 mlRelativeFramePoses / SaveTrajectoryTUM): every
// tracked frame's pose is stored relative to its reference keyframe, T_c_r = T_c_w * T_w_r, so
// that local BA, loop correction and global BA, which move keyframes, move the frames with them.
// When a reference keyframe was culled, the chain continues through its spanning-tree parent
// with KeyFrame::T_c_parent_at_removal() until a live keyframe is reached.
// Thread-safety: add() from the tracking thread; camera_trajectory() from any thread.

#include <cstddef>
#include <mutex>
#include <vector>

#include "ddl/core/se3.h"
#include "ddl/io/trajectory_io.h"
#include "ddl/map/keyframe.h"

namespace ddl::tracking {

class TrajectoryRecorder {
 public:
  /// A tracked frame with pose T_c_w and its reference keyframe.
  void add_tracked(double timestamp_s, const SE3& T_c_w, const map::KeyFramePtr& reference);
  /// A frame that was not tracked (kept for counting; absent from the trajectory).
  void add_lost(double timestamp_s);
  void clear();

  /// T_w_c of every tracked frame, in frame order, from the current keyframe poses.
  io::Trajectory camera_trajectory() const;
  std::size_t frames() const;
  std::size_t tracked_frames() const;

 private:
  struct Entry {
    double timestamp_s;
    SE3 T_c_r;
    map::KeyFramePtr reference;  // nullptr for lost frames
  };
  mutable std::mutex mutex_;
  std::vector<Entry> entries_;
  std::size_t tracked_ = 0;
};

/// T_c_w of a frame stored as T_c_r relative to `reference`, following culled keyframes up the
/// spanning tree.
SE3 resolve_relative_pose(const SE3& T_c_r, const map::KeyFramePtr& reference);

/// A keyframe's pose T_w_c now. A culled keyframe's own pose stops moving when it is culled
/// (local BA, loop correction and global BA only move the map's keyframes); it is followed
/// through its parents, as the camera trajectory is.
SE3 resolved_T_w_c(const map::KeyFramePtr& keyframe);

}  // namespace ddl::tracking
