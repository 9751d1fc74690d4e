#include "ddl/mapping/keyframe_geometry.h"

namespace ddl::mapping {

CameraIntrinsics make_intrinsics(const camera::PinholeCamera& camera, double bf) {
  CameraIntrinsics out;
  out.fx = camera.fx;
  out.fy = camera.fy;
  out.cx = camera.cx;
  out.cy = camera.cy;
  out.bf = bf;
  return out;
}

optimization::Measurement measurement_of(const map::FrameFeatures& features, std::size_t i) {
  const cv::KeyPoint& kp = features.keypoints[i];
  optimization::Measurement m;
  m.uv_px = Vec2d(kp.pt.x, kp.pt.y);
  m.stereo = has_stereo(features, i);
  m.u_right_px = m.stereo ? features.u_right[i] : 0.0;
  m.inv_sigma2 = features.pyramid.inv_level_sigma2[static_cast<std::size_t>(kp.octave)];
  return m;
}

std::optional<Vec3d> unproject_feature_w(const map::FrameFeatures& features, std::size_t i,
                                         const CameraIntrinsics& camera, const SE3& T_c_w) {
  if (i >= features.depth_m.size() || features.depth_m[i] <= 0.0f) return std::nullopt;
  const double z = features.depth_m[i];
  const cv::Point2f& pt = features.keypoints[i].pt;
  const Vec3d p_c((pt.x - camera.cx) / camera.fx * z, (pt.y - camera.cy) / camera.fy * z, z);
  return T_c_w.inverse() * p_c;
}

bool in_image(const map::FrameFeatures& features, const Vec2d& uv) {
  const cv::Rect2f& b = features.grid.bounds();
  return uv.x() >= b.x && uv.y() >= b.y && uv.x() < b.x + b.width && uv.y() < b.y + b.height;
}

double reprojection_chi2(const map::FrameFeatures& features, std::size_t i,
                         const CameraIntrinsics& camera, const Vec3d& p_c) {
  const cv::KeyPoint& kp = features.keypoints[i];
  const Vec2d uv = project(camera, p_c);
  const double du = uv.x() - kp.pt.x;
  const double dv = uv.y() - kp.pt.y;
  double e2 = du * du + dv * dv;
  if (has_stereo(features, i)) {
    const double dr = (uv.x() - camera.bf / p_c.z()) - features.u_right[i];
    e2 += dr * dr;
  }
  return e2 * features.pyramid.inv_level_sigma2[static_cast<std::size_t>(kp.octave)];
}

}  // namespace ddl::mapping
