#include "ddl/camera/depth_reprojection.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace ddl::camera {

cv::Mat reproject_depth(const cv::Mat& depth_m, const SE3& T_target_source,
                        const PinholeCamera& camera) {
  if (depth_m.type() != CV_32FC1 || depth_m.cols != camera.width || depth_m.rows != camera.height) {
    throw std::invalid_argument(
        "reproject_depth: expected a CV_32FC1 depth image of the camera's "
        "size");
  }
  constexpr float kEmpty = std::numeric_limits<float>::infinity();
  cv::Mat out(depth_m.size(), CV_32FC1, cv::Scalar(kEmpty));
  const Eigen::Matrix3f R = T_target_source.rotation().cast<float>();
  const Eigen::Vector3f t = T_target_source.translation().cast<float>();
  const auto fx = static_cast<float>(camera.fx), fy = static_cast<float>(camera.fy);
  const auto cx = static_cast<float>(camera.cx), cy = static_cast<float>(camera.cy);
  const int w = depth_m.cols, h = depth_m.rows;
  for (int v = 0; v < h; ++v) {
    const float* z_row = depth_m.ptr<float>(v);
    const float y = (static_cast<float>(v) - cy) / fy;
    for (int u = 0; u < w; ++u) {
      const float z = z_row[u];
      if (!(z > 0.0f)) continue;
      const Eigen::Vector3f p(z * (static_cast<float>(u) - cx) / fx, z * y, z);
      const Eigen::Vector3f q = R * p + t;
      if (!(q.z() > 1e-3f)) continue;
      const float uf = fx * q.x() / q.z() + cx, vf = fy * q.y() / q.z() + cy;
      const int iu = static_cast<int>(std::lround(uf)), iv = static_cast<int>(std::lround(vf));
      if (iu < 0 || iv < 0 || iu >= w || iv >= h) continue;
      float& cell = out.at<float>(iv, iu);
      cell = std::min(cell, q.z());
    }
  }
  // Cracks: empty pixels inside a splatted surface.
  cv::Mat filled = out.clone();
  for (int v = 1; v + 1 < h; ++v) {
    for (int u = 1; u + 1 < w; ++u) {
      if (out.at<float>(v, u) != kEmpty) continue;
      int neighbours = 0;
      float nearest = kEmpty;
      for (int dv = -1; dv <= 1; ++dv) {
        for (int du = -1; du <= 1; ++du) {
          const float n = out.at<float>(v + dv, u + du);
          if (n == kEmpty) continue;
          ++neighbours;
          nearest = std::min(nearest, n);
        }
      }
      if (neighbours >= 5) filled.at<float>(v, u) = nearest;
    }
  }
  filled.setTo(0.0f, filled == kEmpty);
  return filled;
}

}  // namespace ddl::camera
