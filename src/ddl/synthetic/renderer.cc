#include "ddl/synthetic/renderer.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <opencv2/core/utility.hpp>

namespace ddl::synthetic {
namespace {

/// Brown-Conrady forward model on normalised coordinates (OpenCV order k1 k2 p1 p2 k3).
Vec2d distort(const std::array<double, 5>& k, const Vec2d& p) {
  const double x = p.x();
  const double y = p.y();
  const double r2 = x * x + y * y;
  const double radial = 1 + k[0] * r2 + k[1] * r2 * r2 + k[4] * r2 * r2 * r2;
  return {x * radial + 2 * k[2] * x * y + k[3] * (r2 + 2 * x * x),
          y * radial + k[2] * (r2 + 2 * y * y) + 2 * k[3] * x * y};
}

/// Inverts distort() by Newton's method (numerical Jacobian). Returns false if it does not
/// converge to 1e-10 in normalised units (about 5e-8 px).
bool undistort_newton(const std::array<double, 5>& k, const Vec2d& target, Vec2d& p) {
  p = target;
  for (int it = 0; it < 50; ++it) {
    const Vec2d r = distort(k, p) - target;
    if (r.norm() < 1e-12) return true;
    constexpr double h = 1e-7;
    Eigen::Matrix2d J;
    J.col(0) = (distort(k, p + Vec2d(h, 0)) - distort(k, p - Vec2d(h, 0))) / (2 * h);
    J.col(1) = (distort(k, p + Vec2d(0, h)) - distort(k, p - Vec2d(0, h))) / (2 * h);
    const Vec2d step = J.fullPivLu().solve(r);
    if (!step.allFinite()) return false;
    p -= step;
  }
  return (distort(k, p) - target).norm() < 1e-10;
}

float fast_log2(float x) { return approx_log2(x); }

struct Bbox {
  int u0 = 0, u1 = -1, v0 = 0, v1 = -1;  // inclusive
  bool empty() const { return u1 < u0 || v1 < v0; }
};

}  // namespace

RenderBuffers RenderBuffers::clone() const {
  return {depth_m.clone(), id.clone(), s.clone(), t.clone()};
}

PreparedSurfaces::PreparedSurfaces(const std::vector<Surface>& surfaces,
                                   const std::vector<Texture>& textures, const SE3& T_c_w)
    : surfaces_(&surfaces), textures_(&textures), T_c_w_(T_c_w) {
  planes_.reserve(surfaces.size());
  const Mat3d R = T_c_w.rotation();
  for (const auto& s : surfaces) {
    const Vec3d o = T_c_w * s.origin_w;
    const Vec3d u = R * s.u_w;
    const Vec3d v = R * s.v_w;
    const Vec3d n = u.cross(v).normalized();
    const Vec3d ua = u / u.squaredNorm();
    const Vec3d vb = v / v.squaredNorm();
    Plane p{};
    for (int i = 0; i < 3; ++i) {
      p.n[i] = static_cast<float>(n[i]);
      p.ua[i] = static_cast<float>(ua[i]);
      p.vb[i] = static_cast<float>(vb[i]);
    }
    p.d = static_cast<float>(n.dot(o));
    p.ua0 = static_cast<float>(ua.dot(o));
    p.vb0 = static_cast<float>(vb.dot(o));
    const Texture& tex = textures.at(static_cast<std::size_t>(s.texture));
    const double tw = tex.width() * std::max(1e-6f, s.tex_rect[2] - s.tex_rect[0]);
    const double th = tex.height() * std::max(1e-6f, s.tex_rect[3] - s.tex_rect[1]);
    p.texel_m = static_cast<float>(std::sqrt(u.norm() / tw * v.norm() / th));
    p.alpha = tex.has_alpha();
    planes_.push_back(p);
  }
}

Renderer::Renderer(const camera::PinholeCamera& camera, double near_m)
    : camera_(camera), near_m_(near_m), distorted_(camera.has_distortion()) {
  camera_.validate();
  ray_x_.create(camera.height, camera.width, CV_32FC1);
  ray_y_.create(camera.height, camera.width, CV_32FC1);
  for (int v = 0; v < camera.height; ++v) {
    auto* rx = ray_x_.ptr<float>(v);
    auto* ry = ray_y_.ptr<float>(v);
    for (int u = 0; u < camera.width; ++u) {
      Vec2d p((u - camera.cx) / camera.fx, (v - camera.cy) / camera.fy);
      if (distorted_) {
        Vec2d q;
        if (!undistort_newton(camera.distortion, p, q)) {
          q = Vec2d(std::numeric_limits<double>::quiet_NaN(), 0.0);
        }
        p = q;
      }
      rx[u] = static_cast<float>(p.x());
      ry[u] = static_cast<float>(p.y());
    }
  }
}

Vec3d Renderer::ray(int u, int v) const {
  return {ray_x_.at<float>(v, u), ray_y_.at<float>(v, u), 1.0};
}

RenderBuffers Renderer::make_buffers() const {
  const cv::Size size(camera_.width, camera_.height);
  return {cv::Mat(size, CV_32FC1, cv::Scalar(0)), cv::Mat(size, CV_32SC1, cv::Scalar(-1)),
          cv::Mat(size, CV_32FC1, cv::Scalar(0)), cv::Mat(size, CV_32FC1, cv::Scalar(0))};
}

void Renderer::rasterize(const PreparedSurfaces& prepared, std::size_t begin, std::size_t end,
                         RenderBuffers& buffers) const {
  const int width = camera_.width;
  const int height = camera_.height;
  // Conservative pixel bounding box of each rectangle: clip it to z >= near, project the corners.
  std::vector<Bbox> boxes(end - begin);
  for (std::size_t i = begin; i < end; ++i) {
    const Surface& s = prepared.surfaces()[i];
    const SE3& T = prepared.T_c_w();
    const Vec3d c[4] = {T * s.origin_w, T * (s.origin_w + s.u_w), T * (s.origin_w + s.u_w + s.v_w),
                        T * (s.origin_w + s.v_w)};
    std::vector<Vec3d> poly;
    for (int k = 0; k < 4; ++k) {
      const Vec3d& a = c[k];
      const Vec3d& b = c[(k + 1) % 4];
      const bool ain = a.z() >= near_m_;
      const bool bin = b.z() >= near_m_;
      if (ain) poly.push_back(a);
      if (ain != bin) poly.push_back(a + (b - a) * ((near_m_ - a.z()) / (b.z() - a.z())));
    }
    Bbox& box = boxes[i - begin];
    if (poly.empty()) continue;
    if (distorted_) {
      box = {0, width - 1, 0, height - 1};
      continue;
    }
    double umin = 1e18, umax = -1e18, vmin = 1e18, vmax = -1e18;
    for (const auto& p : poly) {
      const Vec2d uv = camera_.project(p);
      umin = std::min(umin, uv.x());
      umax = std::max(umax, uv.x());
      vmin = std::min(vmin, uv.y());
      vmax = std::max(vmax, uv.y());
    }
    box.u0 = static_cast<int>(std::max(0.0, std::floor(umin) - 1));
    box.u1 = static_cast<int>(std::min(width - 1.0, std::ceil(umax) + 1));
    box.v0 = static_cast<int>(std::max(0.0, std::floor(vmin) - 1));
    box.v1 = static_cast<int>(std::min(height - 1.0, std::ceil(vmax) + 1));
  }
  const float near = static_cast<float>(near_m_);
  const float focal = static_cast<float>(0.5 * (camera_.fx + camera_.fy));
  cv::parallel_for_(cv::Range(0, height), [&](const cv::Range& rows) {
    for (std::size_t i = begin; i < end; ++i) {
      const Bbox& box = boxes[i - begin];
      if (box.empty()) continue;
      const auto& P = prepared.plane(i);
      const Surface& surf = prepared.surfaces()[i];
      const Texture& tex = prepared.textures()[static_cast<std::size_t>(surf.texture)];
      const float s0 = surf.tex_rect[0], t0 = surf.tex_rect[1];
      const float ds = surf.tex_rect[2] - s0, dt = surf.tex_rect[3] - t0;
      const int id = static_cast<int>(i);
      const int v_begin = std::max(rows.start, box.v0);
      const int v_end = std::min(rows.end - 1, box.v1);
      for (int v = v_begin; v <= v_end; ++v) {
        const float* rx = ray_x_.ptr<float>(v);
        const float* ry = ray_y_.ptr<float>(v);
        float* zb = buffers.depth_m.ptr<float>(v);
        int* ib = buffers.id.ptr<int>(v);
        float* sb = buffers.s.ptr<float>(v);
        float* tb = buffers.t.ptr<float>(v);
        for (int u = box.u0; u <= box.u1; ++u) {
          const float x = rx[u];
          const float y = ry[u];
          const float den = P.n[0] * x + P.n[1] * y + P.n[2];
          if (!(std::fabs(den) > 1e-9f)) continue;  // also rejects NaN rays
          const float z = P.d / den;
          if (z <= near || (zb[u] > 0.0f && z >= zb[u])) continue;
          const float a = z * (P.ua[0] * x + P.ua[1] * y + P.ua[2]) - P.ua0;
          if (a < 0.0f || a > 1.0f) continue;
          const float b = z * (P.vb[0] * x + P.vb[1] * y + P.vb[2]) - P.vb0;
          if (b < 0.0f || b > 1.0f) continue;
          float s = s0 + a * ds;
          const float t = t0 + b * dt;
          if (surf.sway != 0.0f) {
            const float w = std::max(0.0f, 1.0f - b / 0.5f);
            s += surf.sway * w * w;
          }
          if (P.alpha) {
            if (s < 0.0f || s > 1.0f) continue;
            const float norm = std::sqrt(x * x + y * y + 1.0f);
            const float cosi = std::max(0.05f, std::fabs(den) / norm);
            const float lod = fast_log2(z * norm / (focal * std::sqrt(cosi) * P.texel_m));
            if (sample_alpha(tex, s, t, lod) < 127.5f) continue;
          }
          zb[u] = z;
          ib[u] = id;
          sb[u] = s;
          tb[u] = t;
        }
      }
    }
  });
}

void Renderer::shade(const PreparedSurfaces& prepared, const RenderBuffers& buffers, int min_id,
                     cv::Mat& rgb, cv::Mat& cos_incidence) const {
  const cv::Size size(camera_.width, camera_.height);
  if (rgb.empty()) rgb = cv::Mat(size, CV_8UC3, cv::Scalar(0, 0, 0));
  if (cos_incidence.empty()) cos_incidence = cv::Mat(size, CV_32FC1, cv::Scalar(0));
  const float focal = static_cast<float>(0.5 * (camera_.fx + camera_.fy));
  cv::parallel_for_(cv::Range(0, size.height), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      const float* rx = ray_x_.ptr<float>(v);
      const float* ry = ray_y_.ptr<float>(v);
      const float* zb = buffers.depth_m.ptr<float>(v);
      const int* ib = buffers.id.ptr<int>(v);
      const float* sb = buffers.s.ptr<float>(v);
      const float* tb = buffers.t.ptr<float>(v);
      auto* out = rgb.ptr<unsigned char>(v);
      auto* cosb = cos_incidence.ptr<float>(v);
      for (int u = 0; u < size.width; ++u) {
        const int id = ib[u];
        if (id < min_id || id < 0) continue;
        const auto& P = prepared.plane(static_cast<std::size_t>(id));
        const Surface& surf = prepared.surfaces()[static_cast<std::size_t>(id)];
        const Texture& tex = prepared.textures()[static_cast<std::size_t>(surf.texture)];
        const float x = rx[u];
        const float y = ry[u];
        const float norm = std::sqrt(x * x + y * y + 1.0f);
        const float cosi = std::fabs(P.n[0] * x + P.n[1] * y + P.n[2]) / norm;
        const float lod =
            fast_log2(zb[u] * norm / (focal * std::sqrt(std::max(0.05f, cosi)) * P.texel_m));
        float c[3];
        sample_mip_nearest(tex, sb[u], tb[u], lod, c);
        for (int k = 0; k < 3; ++k) {
          const float value = c[k] * surf.shade + 0.5f;
          out[3 * u + k] = static_cast<unsigned char>(value > 255.0f ? 255.0f : value);
        }
        cosb[u] = cosi;
      }
    }
  });
}

}  // namespace ddl::synthetic
