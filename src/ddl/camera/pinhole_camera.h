#pragma once
// Pinhole RGB-D camera with Brown-Conrady distortion (OpenCV order k1 k2 p1 p2 k3), as in TUM's
// and ORB-SLAM2's camera files. Coordinates: camera frame x right, y down, z forward (optical
// axis), metres; pixel (u, v) with (0, 0) the centre of the top-left pixel.
// Immutable value type: safe to share between threads.

#include <array>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "ddl/core/types.h"

namespace ddl::camera {

struct PinholeCamera {
  std::string name = "unnamed";                     // e.g. "tum1", shown in logs and summaries
  int width = 640;                                  // image width in pixels
  int height = 480;                                 // image height in pixels
  double fx = 525.0;                                // focal length in pixels, x
  double fy = 525.0;                                // focal length in pixels, y
  double cx = 319.5;                                // principal point, x
  double cy = 239.5;                                // principal point, y
  std::array<double, 5> distortion{0, 0, 0, 0, 0};  // k1 k2 p1 p2 k3 (OpenCV order)
  double depth_factor = 5000.0;                     // raw 16-bit depth value per metre (TUM: 5000)
  double fps = 30.0;                                // nominal frame rate, Hz
  /// When the sensor captured a depth image, relative to the image's own stamp: nullopt means
  /// with its colour image (a synchronised sensor, the generator's rooms), whatever the stamps
  /// say. A value means at the depth stamp plus this offset, seconds; the pipeline then moves the
  /// depth to the colour image's instant (pipeline::DepthTimeAligner, align_depth_in_time).
  std::optional<double> depth_time_offset_s;

  bool has_distortion() const;
  /// Throws ddl::ConfigError naming the field when a value is out of range.
  void validate() const;

  /// Project a point in the camera frame (z > 0) to pixel coordinates (ignores distortion:
  /// images are undistorted on input).
  Vec2d project(const Vec3d& p_c) const {
    return {fx * p_c.x() / p_c.z() + cx, fy * p_c.y() / p_c.z() + cy};
  }
  /// Back-project pixel (u, v) at depth z (metres along the optical axis).
  Vec3d unproject(double u, double v, double depth_m) const {
    return {(u - cx) / fx * depth_m, (v - cy) / fy * depth_m, depth_m};
  }
  bool in_image(const Vec2d& uv, double border = 0.0) const {
    return uv.x() >= border && uv.y() >= border && uv.x() <= width - 1 - border &&
           uv.y() <= height - 1 - border;
  }
  cv::Matx33d K() const { return {fx, 0, cx, 0, fy, cy, 0, 0, 1}; }
  /// The same camera without distortion (what frames look like after undistortion).
  PinholeCamera undistorted() const;
};

/// Undistorts images of a distorted camera into its undistorted() twin, with maps precomputed once.
/// RGB is interpolated bilinearly; depth by nearest neighbour (never blends across depth edges).
/// Thread-safe after construction (const methods only).
class Undistorter {
 public:
  explicit Undistorter(const PinholeCamera& camera);
  bool active() const { return active_; }
  cv::Mat undistort_rgb(const cv::Mat& rgb) const;
  cv::Mat undistort_depth(const cv::Mat& depth) const;
  /// CV_8UC1, 255 where an undistorted pixel has a source pixel in the stored image (exactly the
  /// pixels undistort_depth can fill), 0 in the blank margin undistortion leaves; empty when not
  /// active. A band the stored depth never measures (a Kinect's, along the top and right of fr1's
  /// depth images) is not known here and lies inside the area.
  const cv::Mat& source_area() const { return source_area_; }

 private:
  bool active_ = false;
  cv::Mat source_area_;
  cv::Mat map_xy_, map_interpolation_;  // fixed-point colour maps (CV_16SC2, CV_16UC1)
  cv::Mat map_nearest_;                 // fixed-point depth map, rounded positions (CV_16SC2)
};

}  // namespace ddl::camera
