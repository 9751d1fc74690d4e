#include "ddl/camera/pinhole_camera.h"

#include <fmt/format.h>

#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>

#include "ddl/core/error.h"

namespace ddl::camera {

bool PinholeCamera::has_distortion() const {
  for (double d : distortion) {
    if (d != 0.0) return true;
  }
  return false;
}

void PinholeCamera::validate() const {
  auto require = [](bool ok, const char* key, double value, const char* what) {
    if (!ok) throw ConfigError::for_key(key, fmt::format("{} (got {})", what, value));
  };
  require(width > 0 && width <= 16384, "camera.width", width, "must be in 1..16384");
  require(height > 0 && height <= 16384, "camera.height", height, "must be in 1..16384");
  require(std::isfinite(fx) && fx > 0, "camera.fx", fx, "must be a positive focal length");
  require(std::isfinite(fy) && fy > 0, "camera.fy", fy, "must be a positive focal length");
  require(std::isfinite(cx) && cx >= 0 && cx <= width, "camera.cx", cx,
          "must lie inside the image");
  require(std::isfinite(cy) && cy >= 0 && cy <= height, "camera.cy", cy,
          "must lie inside the image");
  for (double d : distortion) require(std::isfinite(d), "camera.distortion", d, "must be finite");
  require(std::isfinite(depth_factor) && depth_factor > 0, "camera.depth_factor", depth_factor,
          "must be positive (raw units per metre)");
  require(std::isfinite(fps) && fps > 0, "camera.fps", fps, "must be positive");
}

PinholeCamera PinholeCamera::undistorted() const {
  PinholeCamera out = *this;
  out.distortion = {0, 0, 0, 0, 0};
  return out;
}

Undistorter::Undistorter(const PinholeCamera& camera) : active_(camera.has_distortion()) {
  if (!active_) return;
  const cv::Mat K(camera.K());
  const cv::Mat dist(1, 5, CV_64F, const_cast<double*>(camera.distortion.data()));
  // Fixed-point maps run remap about twice as fast as float maps: for colour, integer positions
  // plus a 1/32-pixel interpolation table; for depth, positions rounded to the nearest pixel
  // (nninterpolation), so depth values are never blended and match a float-map nearest lookup.
  cv::Mat map_x, map_y;
  cv::initUndistortRectifyMap(K, dist, cv::Mat(), K, cv::Size(camera.width, camera.height),
                              CV_32FC1, map_x, map_y);
  cv::convertMaps(map_x, map_y, map_xy_, map_interpolation_, CV_16SC2, false);
  cv::Mat unused;
  cv::convertMaps(map_x, map_y, map_nearest_, unused, CV_16SC2, true);
  const cv::Mat everywhere(camera.height, camera.width, CV_8UC1, cv::Scalar(255));
  cv::remap(everywhere, source_area_, map_nearest_, cv::Mat(), cv::INTER_NEAREST,
            cv::BORDER_CONSTANT, cv::Scalar(0));
}

cv::Mat Undistorter::undistort_rgb(const cv::Mat& rgb) const {
  if (!active_) return rgb;
  cv::Mat out;
  cv::remap(rgb, out, map_xy_, map_interpolation_, cv::INTER_LINEAR, cv::BORDER_CONSTANT);
  return out;
}

cv::Mat Undistorter::undistort_depth(const cv::Mat& depth) const {
  if (!active_) return depth;
  cv::Mat out;
  cv::remap(depth, out, map_nearest_, cv::Mat(), cv::INTER_NEAREST, cv::BORDER_CONSTANT);
  return out;
}

}  // namespace ddl::camera
