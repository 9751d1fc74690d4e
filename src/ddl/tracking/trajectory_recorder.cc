#include "ddl/tracking/trajectory_recorder.h"

namespace ddl::tracking {

SE3 resolve_relative_pose(const SE3& T_c_r, const map::KeyFramePtr& reference) {
  SE3 T_c_k = T_c_r;
  map::KeyFramePtr kf = reference;
  // A culled keyframe keeps T_c_parent at removal; its parent may have been culled later too.
  while (kf->is_bad()) {
    map::KeyFramePtr parent = kf->parent();
    if (!parent) break;
    T_c_k = T_c_k * kf->T_c_parent_at_removal();
    kf = std::move(parent);
  }
  return T_c_k * kf->T_c_w();
}

SE3 resolved_T_w_c(const map::KeyFramePtr& keyframe) {
  return resolve_relative_pose(SE3(), keyframe).inverse();
}

void TrajectoryRecorder::add_tracked(double timestamp_s, const SE3& T_c_w,
                                     const map::KeyFramePtr& reference) {
  std::lock_guard lock(mutex_);
  entries_.push_back(Entry{timestamp_s, T_c_w * reference->T_w_c(), reference});
  ++tracked_;
}

void TrajectoryRecorder::add_lost(double timestamp_s) {
  std::lock_guard lock(mutex_);
  entries_.push_back(Entry{timestamp_s, SE3(), nullptr});
}

void TrajectoryRecorder::clear() {
  std::lock_guard lock(mutex_);
  entries_.clear();
  tracked_ = 0;
}

io::Trajectory TrajectoryRecorder::camera_trajectory() const {
  std::vector<Entry> entries;
  {
    std::lock_guard lock(mutex_);
    entries = entries_;
  }
  io::Trajectory trajectory;
  trajectory.reserve(entries.size());
  for (const Entry& e : entries) {
    if (!e.reference) continue;
    trajectory.emplace_back(e.timestamp_s, resolve_relative_pose(e.T_c_r, e.reference).inverse());
  }
  return trajectory;
}

std::size_t TrajectoryRecorder::frames() const {
  std::lock_guard lock(mutex_);
  return entries_.size();
}

std::size_t TrajectoryRecorder::tracked_frames() const {
  std::lock_guard lock(mutex_);
  return tracked_;
}

}  // namespace ddl::tracking
