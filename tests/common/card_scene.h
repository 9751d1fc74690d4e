#pragma once
// Shared by the test suites: the depth image of a small analytic scene, a wall at z_w = 3 m and
// a 0.5 m square card at z_w = 1.5 m centred on the world's z axis, for tests that move depth
// images between poses. Include as "card_scene.h".

#include <cmath>
#include <opencv2/core.hpp>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"

namespace ddl::test_support {

/// A 320x240 camera without distortion, 63 degrees wide.
inline camera::PinholeCamera card_scene_camera() {
  camera::PinholeCamera c;
  c.width = 320;
  c.height = 240;
  c.fx = c.fy = 260.0;
  c.cx = 159.5;
  c.cy = 119.5;
  return c;
}

/// Depth (CV_32FC1, metres along the optical axis) of the scene seen by `cam` at `T_w_c`.
inline cv::Mat render_card_scene(const camera::PinholeCamera& cam, const SE3& T_w_c) {
  cv::Mat depth(cam.height, cam.width, CV_32FC1, cv::Scalar(0.0f));
  const Mat3d R = T_w_c.rotation();
  const Vec3d o = T_w_c.translation();
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Vec3d ray_w = R * cam.unproject(u, v, 1.0);  // z = 1 in the camera: s is the depth
      double best = 0.0;
      for (const double plane_z : {1.5, 3.0}) {
        const double s = (plane_z - o.z()) / ray_w.z();
        if (s <= 0) continue;
        const Vec3d p = o + s * ray_w;
        if (plane_z == 1.5 && (std::abs(p.x()) > 0.25 || std::abs(p.y()) > 0.25)) continue;
        if (best == 0.0 || s < best) best = s;
      }
      depth.at<float>(v, u) = static_cast<float>(best);
    }
  }
  return depth;
}

}  // namespace ddl::test_support
