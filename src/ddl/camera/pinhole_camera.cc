#include "ddl/camera/pinhole_camera.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <opencv2/calib3d.hpp>
#include <opencv2/imgproc.hpp>
#include <vector>

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
  // A focal length no lens has: the field of view across the image must be 1-170 degrees.
  const auto fov_deg = [](double size, double f) {
    return 2.0 * std::atan(0.5 * size / f) * 180.0 / M_PI;
  };
  const double fov_x = fov_deg(width, fx);
  const double fov_y = fov_deg(height, fy);
  require(fov_x >= 1.0 && fov_x <= 170.0, "camera.fx", fx,
          fmt::format("gives a horizontal field of view of {:.3g} degrees over {} px; must be "
                      "1-170 degrees",
                      fov_x, width)
              .c_str());
  require(fov_y >= 1.0 && fov_y <= 170.0, "camera.fy", fy,
          fmt::format("gives a vertical field of view of {:.3g} degrees over {} px; must be "
                      "1-170 degrees",
                      fov_y, height)
              .c_str());
  require(std::isfinite(cx) && cx >= 0 && cx <= width, "camera.cx", cx,
          "must lie inside the image");
  require(std::isfinite(cy) && cy >= 0 && cy <= height, "camera.cy", cy,
          "must lie inside the image");
  for (double d : distortion) require(std::isfinite(d), "camera.distortion", d, "must be finite");
  // 16-bit depth: below 0.1 units per metre one unit would be over 10 m.
  require(std::isfinite(depth_factor) && depth_factor >= 0.1 && depth_factor <= 1e6,
          "camera.depth_factor", depth_factor, "must be in 0.1..1e6 (raw units per metre)");
  require(std::isfinite(fps) && fps > 0, "camera.fps", fps, "must be positive");
  if (depth_time_offset_s) {
    require(std::isfinite(*depth_time_offset_s) && std::abs(*depth_time_offset_s) <= 0.1,
            "camera.depth_time_offset_s", *depth_time_offset_s,
            "must be in -0.1..0.1 seconds (a frame interval or two at most)");
  }
  if (has_distortion()) {
    // Coefficients no lens has send most of the undistorted image outside the sensor. Each
    // undistorted pixel of a 64 x 48 grid is distorted by OpenCV's model (the one the
    // undistortion maps invert) and must land on the sensor for at least half of them.
    constexpr int kCols = 64, kRows = 48;
    std::vector<cv::Point3d> rays;  // normalised undistorted coordinates at depth 1
    for (int r = 0; r < kRows; ++r) {
      for (int c = 0; c < kCols; ++c) {
        rays.emplace_back(((c + 0.5) * width / kCols - cx) / fx,
                          ((r + 0.5) * height / kRows - cy) / fy, 1.0);
      }
    }
    std::vector<cv::Point2d> distorted;
    cv::projectPoints(rays, cv::Vec3d(), cv::Vec3d(), cv::Mat(K()),
                      cv::Mat(1, 5, CV_64F, const_cast<double*>(distortion.data())), distorted);
    const auto inside =
        std::count_if(distorted.begin(), distorted.end(), [&](const cv::Point2d& p) {
          return p.x >= 0.0 && p.x < width && p.y >= 0.0 && p.y < height;
        });
    const double covered = static_cast<double>(inside) / static_cast<double>(kCols * kRows);
    if (covered < 0.5) {
      throw ConfigError::for_key(
          "camera.distortion",
          fmt::format("leaves only {:.0f}% of the undistorted image with a source pixel (at least "
                      "50% expected): coefficients no lens has?",
                      100.0 * covered));
    }
  }
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
