#include "ddl/pipeline/depth_time_aligner.h"

#include <cmath>

#include "ddl/camera/depth_reprojection.h"

namespace ddl::pipeline {
namespace {

constexpr double kMinShiftS = 1e-4;  // below this no sensor moves a pixel

}  // namespace

DepthTimeAligner::DepthTimeAligner(const camera::PinholeCamera& camera, bool enabled)
    : camera_(camera), active_(enabled && camera.depth_time_offset_s.has_value()) {}

double DepthTimeAligner::shift_s(const io::RgbdFrame& frame) const {
  if (!active_) return 0.0;
  return frame.depth_timestamp_s.value_or(frame.timestamp_s) + *camera_.depth_time_offset_s -
         frame.timestamp_s;
}

cv::Mat DepthTimeAligner::align(const io::RgbdFrame& frame, const std::optional<SE3>& velocity,
                                double interval_s, DepthAlignment* alignment) const {
  DepthAlignment a;
  a.shift_s = shift_s(frame);
  if (alignment != nullptr) *alignment = a;
  if (!active_ || !velocity || !(interval_s > 0.0) || std::abs(a.shift_s) < kMinShiftS ||
      frame.depth_m.empty()) {
    return frame.depth_m;
  }
  // velocity = T_{c(t)}_{c(t - interval)}: over a time s the camera moves by
  // T_{c(t + s)}_{c(t)} = exp(s / interval * log(velocity)). The depth camera is c(t + shift):
  // its points go into the colour camera c(t) by the inverse of that motion.
  const Vec6d xi = velocity->log() * (a.shift_s / interval_s);
  const SE3 T_rgb_depth = SE3::exp(-xi);
  a.moved = true;
  a.rotation_deg = T_rgb_depth.rotation_angle() * 180.0 / M_PI;
  if (alignment != nullptr) *alignment = a;
  return camera::reproject_depth(frame.depth_m, T_rgb_depth, camera_);
}

}  // namespace ddl::pipeline
