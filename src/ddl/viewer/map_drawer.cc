#include "ddl/viewer/map_drawer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace ddl::viewer {
namespace {

constexpr double kNearPlaneM = 0.02;
const cv::Scalar kBackground(40, 40, 40);
const cv::Scalar kPointColour(200, 200, 200);
const cv::Scalar kKeyframeColour(255, 140, 40);
const cv::Scalar kTreeColour(90, 200, 90);
const cv::Scalar kCameraColour(40, 40, 255);

// Clips the segment a-b to the box (Liang-Barsky, in double: cv::line takes int coordinates,
// which far-off projections would overflow). False when nothing of it is inside.
bool clip_segment(cv::Point2d& a, cv::Point2d& b, const cv::Rect2d& box) {
  if (!std::isfinite(a.x) || !std::isfinite(a.y) || !std::isfinite(b.x) || !std::isfinite(b.y)) {
    return false;
  }
  const cv::Point2d d = b - a;
  const std::array<double, 4> p = {-d.x, d.x, -d.y, d.y};
  const std::array<double, 4> q = {a.x - box.x, box.x + box.width - a.x, a.y - box.y,
                                   box.y + box.height - a.y};
  double t0 = 0.0, t1 = 1.0;
  for (std::size_t i = 0; i < 4; ++i) {
    if (p[i] == 0.0) {
      if (q[i] < 0.0) return false;
      continue;
    }
    const double t = q[i] / p[i];
    if (p[i] < 0.0) {
      if (t > t1) return false;
      t0 = std::max(t0, t);
    } else {
      if (t < t0) return false;
      t1 = std::min(t1, t);
    }
  }
  const cv::Point2d a0 = a;
  a = a0 + t0 * d;
  b = a0 + t1 * d;
  return true;
}

struct Projector {
  const MapView& view;
  cv::Point2d to_pixel(const Vec3d& p_v) const {
    return {view.focal_px * p_v.x() / p_v.z() + 0.5 * view.width,
            view.focal_px * p_v.y() / p_v.z() + 0.5 * view.height};
  }
  bool project(const Vec3d& p_v, cv::Point2d& uv) const {
    if (p_v.z() < kNearPlaneM) return false;
    uv = to_pixel(p_v);
    return true;
  }
  // A segment in world coordinates, clipped at the near plane and to a margin around the image.
  void line(cv::Mat& image, const Vec3d& a_w, const Vec3d& b_w, const cv::Scalar& colour,
            int thickness) const {
    Vec3d a = view.T_v_w * a_w;
    Vec3d b = view.T_v_w * b_w;
    if (a.z() < kNearPlaneM && b.z() < kNearPlaneM) return;
    if (a.z() < kNearPlaneM) std::swap(a, b);
    if (b.z() < kNearPlaneM) {
      b = a + (b - a) * ((a.z() - kNearPlaneM) / (a.z() - b.z()));
      b.z() = kNearPlaneM;  // exactly on the plane, whatever the rounding
    }
    cv::Point2d ua = to_pixel(a), ub = to_pixel(b);
    const cv::Rect2d box(-view.width, -view.height, 3.0 * view.width, 3.0 * view.height);
    if (!clip_segment(ua, ub, box)) return;
    cv::line(image, cv::Point(cvRound(ua.x), cvRound(ua.y)),
             cv::Point(cvRound(ub.x), cvRound(ub.y)), colour, thickness, cv::LINE_AA);
  }
};

// A camera frustum of `size` metres (ORB-SLAM2's keyframe drawing: w, 0.75 w, 0.6 w).
void draw_frustum(cv::Mat& image, const Projector& projector, const SE3& T_w_c, double size,
                  const cv::Scalar& colour, int thickness) {
  const double w = size, h = 0.75 * size, z = 0.6 * size;
  const Vec3d o = T_w_c.translation();
  const std::array<Vec3d, 4> corners = {T_w_c * Vec3d(w, h, z), T_w_c * Vec3d(w, -h, z),
                                        T_w_c * Vec3d(-w, -h, z), T_w_c * Vec3d(-w, h, z)};
  for (std::size_t i = 0; i < 4; ++i) {
    projector.line(image, o, corners[i], colour, thickness);
    projector.line(image, corners[i], corners[(i + 1) % 4], colour, thickness);
  }
}

}  // namespace

MapSnapshot snapshot_map(const map::Map& map) {
  MapSnapshot snapshot;
  map.read_consistent([&] {
    const std::vector<map::MapPointPtr> points = map.map_points();
    snapshot.points_w.reserve(points.size());
    for (const map::MapPointPtr& p : points) snapshot.points_w.push_back(p->position_w());
    const std::vector<map::KeyFramePtr> keyframes = map.keyframes();
    snapshot.keyframes_T_w_c.reserve(keyframes.size());
    for (const map::KeyFramePtr& kf : keyframes) {
      snapshot.keyframes_T_w_c.push_back(kf->T_w_c());
      if (const map::KeyFramePtr parent = kf->parent()) {
        snapshot.tree_edges_w.emplace_back(kf->camera_center_w(), parent->camera_center_w());
      }
    }
  });
  return snapshot;
}

SE3 look_at(const Vec3d& eye_w, const Vec3d& target_w, const Vec3d& down_w) {
  const Vec3d forward = target_w - eye_w;
  if (forward.norm() < 1e-9) throw std::invalid_argument("look_at: eye and target coincide");
  const Vec3d z = forward.normalized();
  const Vec3d x_raw = down_w.cross(z);
  if (x_raw.norm() < 1e-9) {
    throw std::invalid_argument("look_at: the view direction is parallel to the down axis");
  }
  const Vec3d x = x_raw.normalized();
  const Vec3d y = z.cross(x);
  Mat3d R_v_w;
  R_v_w.row(0) = x.transpose();
  R_v_w.row(1) = y.transpose();
  R_v_w.row(2) = z.transpose();
  return SE3(R_v_w, -(R_v_w * eye_w));
}

SE3 follow_view(const SE3& T_w_c, double back_m, double up_m) {
  const Vec3d eye_w = T_w_c * Vec3d(0.0, -up_m, -back_m);
  const Vec3d down_w = T_w_c.rotation() * Vec3d(0.0, 1.0, 0.0);
  return look_at(eye_w, T_w_c.translation(), down_w);
}

cv::Mat draw_map(const MapSnapshot& map, const std::optional<SE3>& current_T_w_c,
                 const MapView& view) {
  if (view.width <= 0 || view.height <= 0 || !(view.focal_px > 0.0)) {
    throw std::invalid_argument("draw_map: the view needs a positive size and focal length");
  }
  cv::Mat image(view.height, view.width, CV_8UC3, kBackground);
  const Projector projector{view};
  for (const Vec3d& p_w : map.points_w) {
    cv::Point2d uv;
    if (!projector.project(view.T_v_w * p_w, uv)) continue;
    // 2x2 pixels, like ORB-SLAM2's glPointSize(2).
    if (!(uv.x >= 0.0 && uv.y >= 0.0 && uv.x < view.width - 1 && uv.y < view.height - 1)) continue;
    const int u = static_cast<int>(uv.x), v = static_cast<int>(uv.y);
    image(cv::Rect(u, v, 2, 2)).setTo(kPointColour);
  }
  for (const auto& [a, b] : map.tree_edges_w) projector.line(image, a, b, kTreeColour, 1);
  for (const SE3& T_w_c : map.keyframes_T_w_c) {
    draw_frustum(image, projector, T_w_c, 0.05, kKeyframeColour, 1);
  }
  if (current_T_w_c) draw_frustum(image, projector, *current_T_w_c, 0.08, kCameraColour, 2);
  return image;
}

}  // namespace ddl::viewer
