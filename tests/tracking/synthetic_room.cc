#include "synthetic_room.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/imgproc.hpp>

namespace ddl::tracking::testing {
namespace {

constexpr double kTexelsPerMetre = 250.0;  // 4 mm texels: about one image pixel at 2.5 m

cv::Mat make_texture(int rows, int cols, cv::RNG& rng) {
  cv::Mat texture(rows, cols, CV_32F, cv::Scalar(rng.uniform(90.0, 160.0)));
  const double area_m2 = rows * cols / (kTexelsPerMetre * kTexelsPerMetre);
  const int shapes = static_cast<int>(area_m2 * 220.0);
  for (int s = 0; s < shapes; ++s) {
    const cv::Point c(rng.uniform(0, cols), rng.uniform(0, rows));
    const double grey = rng.uniform(0.0, 255.0);
    const int kind = rng.uniform(0, 3);
    if (kind == 0) {
      const int w = rng.uniform(4, 60);
      const int h = rng.uniform(4, 60);
      cv::rectangle(texture, cv::Rect(c.x - w / 2, c.y - h / 2, w, h), cv::Scalar(grey),
                    cv::FILLED);
    } else if (kind == 1) {
      cv::circle(texture, c, rng.uniform(3, 30), cv::Scalar(grey), cv::FILLED, cv::LINE_AA);
    } else {
      // Small speckles: fine-scale corners.
      const int w = rng.uniform(2, 6);
      cv::rectangle(texture, cv::Rect(c.x, c.y, w, w), cv::Scalar(grey), cv::FILLED);
    }
  }
  cv::GaussianBlur(texture, texture, cv::Size(3, 3), 0.7);
  return texture;
}

float sample_bilinear(const cv::Mat& texture, double x, double y) {
  x = std::clamp(x, 0.0, texture.cols - 1.001);
  y = std::clamp(y, 0.0, texture.rows - 1.001);
  const int x0 = static_cast<int>(x);
  const int y0 = static_cast<int>(y);
  const float ax = static_cast<float>(x - x0);
  const float ay = static_cast<float>(y - y0);
  const float* r0 = texture.ptr<float>(y0);
  const float* r1 = texture.ptr<float>(y0 + 1);
  const float top = r0[x0] * (1.0f - ax) + r0[x0 + 1] * ax;
  const float bottom = r1[x0] * (1.0f - ax) + r1[x0 + 1] * ax;
  return top * (1.0f - ay) + bottom * ay;
}

}  // namespace

int SyntheticRoom::add_face(int axis, double position, double u_extent_m, double v_extent_m,
                            double u0, double v0, cv::RNG& rng) {
  Face face;
  face.axis = axis;
  face.position = position;
  face.u_axis = axis == 0 ? 2 : 0;
  face.v_axis = axis == 1 ? 2 : 1;
  face.u0 = u0;
  face.v0 = v0;
  face.texture = make_texture(static_cast<int>(std::ceil(v_extent_m * kTexelsPerMetre)) + 2,
                              static_cast<int>(std::ceil(u_extent_m * kTexelsPerMetre)) + 2, rng);
  faces_.push_back(std::move(face));
  return static_cast<int>(faces_.size()) - 1;
}

SyntheticRoom::SyntheticRoom(std::uint64_t seed) {
  cv::RNG rng(seed);
  auto add_box_faces = [&](const Vec3d& lo, const Vec3d& hi) {
    int first = -1;
    for (int axis = 0; axis < 3; ++axis) {
      const int ua = axis == 0 ? 2 : 0;
      const int va = axis == 1 ? 2 : 1;
      for (int side = 0; side < 2; ++side) {
        const int index = add_face(axis, side == 0 ? lo[axis] : hi[axis], hi[ua] - lo[ua],
                                   hi[va] - lo[va], lo[ua], lo[va], rng);
        if (first < 0) first = index;
      }
    }
    return first;
  };
  room_first_face_ = add_box_faces(room_min_, room_max_);
  const std::vector<std::pair<Vec3d, Vec3d>> boxes = {
      {Vec3d(-1.1, 0.3, 1.2), Vec3d(-0.4, 1.2, 1.8)},
      {Vec3d(0.5, -0.3, 1.5), Vec3d(1.1, 1.2, 1.9)},
  };
  for (const auto& [lo, hi] : boxes) boxes_.push_back(Box{lo, hi, add_box_faces(lo, hi)});
}

float SyntheticRoom::shade(const Face& face, const Vec3d& p) const {
  const double x = (p[face.u_axis] - face.u0) * kTexelsPerMetre;
  const double y = (p[face.v_axis] - face.v0) * kTexelsPerMetre;
  return sample_bilinear(face.texture, x, y);
}

io::RgbdFrame SyntheticRoom::render(const camera::PinholeCamera& camera, const SE3& T_w_c,
                                    std::size_t index, double timestamp_s,
                                    double noise_sigma) const {
  io::RgbdFrame frame;
  frame.index = index;
  frame.timestamp_s = timestamp_s;
  cv::Mat grey(camera.height, camera.width, CV_32F);
  frame.depth_m = cv::Mat(camera.height, camera.width, CV_32F);
  const Mat3d R = T_w_c.rotation();
  const Vec3d o = T_w_c.translation();
  for (int v = 0; v < camera.height; ++v) {
    float* grey_row = grey.ptr<float>(v);
    float* depth_row = frame.depth_m.ptr<float>(v);
    for (int u = 0; u < camera.width; ++u) {
      // Ray with unit z in the camera frame: the hit parameter is the depth.
      const Vec3d d = R * Vec3d((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy, 1.0);
      double t_best = std::numeric_limits<double>::infinity();
      int face_best = -1;
      for (int k = 0; k < 3; ++k) {
        if (d[k] == 0.0) continue;
        const bool positive = d[k] > 0.0;
        const double t = ((positive ? room_max_[k] : room_min_[k]) - o[k]) / d[k];
        if (t > 0.0 && t < t_best) {
          t_best = t;
          face_best = room_first_face_ + 2 * k + (positive ? 1 : 0);
        }
      }
      for (const Box& box : boxes_) {
        double t_near = -std::numeric_limits<double>::infinity();
        double t_far = std::numeric_limits<double>::infinity();
        int near_face = -1;
        for (int k = 0; k < 3; ++k) {
          if (d[k] == 0.0) {
            if (o[k] < box.min[k] || o[k] > box.max[k]) t_near = t_far + 1.0;
            continue;
          }
          double t1 = (box.min[k] - o[k]) / d[k];
          double t2 = (box.max[k] - o[k]) / d[k];
          int face = box.first_face + 2 * k;  // entering through the min side
          if (t1 > t2) {
            std::swap(t1, t2);
            face = box.first_face + 2 * k + 1;
          }
          if (t1 > t_near) {
            t_near = t1;
            near_face = face;
          }
          t_far = std::min(t_far, t2);
        }
        if (t_near <= t_far && t_near > 0.0 && t_near < t_best) {
          t_best = t_near;
          face_best = near_face;
        }
      }
      const Vec3d p = o + t_best * d;
      grey_row[u] = shade(faces_[static_cast<std::size_t>(face_best)], p);
      depth_row[u] = static_cast<float>(t_best);
    }
  }
  if (noise_sigma > 0.0) {
    cv::Mat noise(grey.size(), CV_32F);
    cv::RNG rng(0x9E3779B97F4A7C15ULL ^ static_cast<std::uint64_t>(index));
    rng.fill(noise, cv::RNG::NORMAL, 0.0, noise_sigma);
    grey += noise;
  }
  cv::Mat grey8;
  grey.convertTo(grey8, CV_8U);
  cv::cvtColor(grey8, frame.rgb, cv::COLOR_GRAY2BGR);
  return frame;
}

std::vector<SE3> smooth_trajectory(int frames) {
  std::vector<SE3> poses;
  poses.reserve(static_cast<std::size_t>(frames));
  constexpr double kDeg = M_PI / 180.0;
  for (int k = 0; k < frames; ++k) {
    const double ph = 2.0 * M_PI * k / 40.0;
    const Vec3d t(0.15 * std::sin(ph), 0.05 * std::sin(2.0 * ph), 0.10 * (1.0 - std::cos(ph)));
    const Vec3d rotation(3.0 * kDeg * std::sin(2.0 * ph + 0.5), 6.0 * kDeg * std::sin(ph),
                         2.0 * kDeg * std::sin(ph));
    poses.emplace_back(so3_exp(rotation), t);
  }
  return poses;
}

}  // namespace ddl::tracking::testing
