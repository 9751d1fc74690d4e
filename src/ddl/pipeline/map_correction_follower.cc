#include "ddl/pipeline/map_correction_follower.h"

#include "ddl/tracking/trajectory_recorder.h"

namespace ddl::pipeline {

bool MapCorrectionFollower::anchor(const map::KeyFramePtr& reference,
                                   std::uint64_t frame_changes_at_tracking) {
  bool anchored = false;
  map_->read_consistent([&] {
    if (map_->frame_change_count() != frame_changes_at_tracking) return;
    anchor_ = reference;
    seen_frame_changes_ = frame_changes_at_tracking;
    T_w_anchor_ = tracking::resolved_T_w_c(anchor_);
    anchored = true;
  });
  return anchored;
}

std::optional<SE3> MapCorrectionFollower::correction() {
  if (!anchor_ || map_->frame_change_count() == seen_frame_changes_) return std::nullopt;
  SE3 T_w_anchor_now;
  map_->read_consistent([&] {
    seen_frame_changes_ = map_->frame_change_count();
    T_w_anchor_now = tracking::resolved_T_w_c(anchor_);
  });
  const SE3 T_new_old = T_w_anchor_now * T_w_anchor_.inverse();
  T_w_anchor_ = T_w_anchor_now;
  return T_new_old;
}

}  // namespace ddl::pipeline
