#pragma once
// Depth images captured at another instant than their colour images (TUM's Freiburg 1 Kinect:
// the depth stamp differs from the RGB stamp by up to +-20 ms, and the depth was captured about
// 20 ms before its stamp; docs/dynamics.md, "Depth in time"). On a fast rotation the depth
// image is then several pixels off the colour image and off the pose tracking estimates from the
// colour image's keypoints: depth edges fall on the wrong surfaces, and the free-space check
// takes the desk's edge for something standing in space other keyframes saw empty. The aligner
// moves the depth image to the colour image's instant, taking the motion between two tracked
// frames as constant (System: from the previous frame's pose to the low-cost pose).
// Threads: const after construction; System calls it from the tracking thread.

#include <opencv2/core.hpp>
#include <optional>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"
#include "ddl/io/rgbd_frame.h"

namespace ddl::pipeline {

/// What align() did to one frame.
struct DepthAlignment {
  bool moved = false;         // the depth image was reprojected
  double shift_s = 0.0;       // depth capture instant minus the colour image's, seconds
  double rotation_deg = 0.0;  // the camera's rotation over shift_s, by the motion model
};

class DepthTimeAligner {
 public:
  /// `camera` is the undistorted camera of the frames; nothing is ever moved when `enabled` is
  /// false or the camera has no depth_time_offset_s (its depth is captured with the colour).
  DepthTimeAligner(const camera::PinholeCamera& camera, bool enabled);

  /// Whether frames may be moved at all (enabled, and the camera has an offset).
  bool active() const { return active_; }

  /// The depth capture instant of `frame` minus its colour image's, seconds: the depth stamp
  /// (the RGB stamp without one) plus the camera's offset, minus the RGB stamp. 0 when inactive.
  double shift_s(const io::RgbdFrame& frame) const;

  /// `frame`'s depth image at its colour image's instant. `velocity` is T_c(k)_c(k-1), from the
  /// camera of an earlier frame into this frame's colour camera, `interval_s` seconds apart; the
  /// motion is taken as constant over the shift. Without
  /// a velocity (the first frame, after a loss or a relocalization), or for a shift under
  /// 0.1 ms, the image is returned as it is. `alignment` (optional) tells what happened.
  cv::Mat align(const io::RgbdFrame& frame, const std::optional<SE3>& velocity, double interval_s,
                DepthAlignment* alignment) const;

 private:
  camera::PinholeCamera camera_;
  bool active_;
};

}  // namespace ddl::pipeline
