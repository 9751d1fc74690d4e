#include "ddl/pipeline/map_correction_follower.h"

#include "ddl/tracking/trajectory_recorder.h"

namespace ddl::pipeline {

void MapCorrectionFollower::anchor(const map::KeyFramePtr& reference) {
  anchor_ = reference;
  map_->read_consistent([&] {
    seen_big_change_ = map_->big_change_index();
    T_w_anchor_ = tracking::resolved_T_w_c(anchor_);
  });
}

std::optional<SE3> MapCorrectionFollower::correction() {
  if (!anchor_ || map_->big_change_index() == seen_big_change_) return std::nullopt;
  SE3 T_w_anchor_now;
  map_->read_consistent([&] {
    seen_big_change_ = map_->big_change_index();
    T_w_anchor_now = tracking::resolved_T_w_c(anchor_);
  });
  const SE3 T_new_old = T_w_anchor_now * T_w_anchor_.inverse();
  T_w_anchor_ = T_w_anchor_now;
  return T_new_old;
}

}  // namespace ddl::pipeline
