#pragma once
// Constant-velocity motion model (ORB-SLAM2 Tracking::TrackWithMotionModel): the relative motion
// between the last two tracked frames is assumed to repeat, T_c_w(k+1) = V * T_c_w(k) with
// V = T_c_w(k) * T_w_c(k-1) (the previous camera in the current camera's frame).

#include "ddl/core/se3.h"

namespace ddl::tracking {

class MotionModel {
 public:
  bool valid() const { return valid_; }
  void reset() { valid_ = false; }
  /// Learns V from the pose of the frame just tracked and the pose of the one before it.
  void update(const SE3& T_c_w_current, const SE3& T_c_w_previous) {
    velocity_ = T_c_w_current * T_c_w_previous.inverse();
    valid_ = true;
  }
  /// Predicted T_c_w of the next frame (precondition: valid()).
  SE3 predict(const SE3& T_c_w_last) const { return velocity_ * T_c_w_last; }
  /// V = T_current_previous.
  const SE3& velocity() const { return velocity_; }

 private:
  SE3 velocity_;
  bool valid_ = false;
};

}  // namespace ddl::tracking
