#include "ddl/dynamics/dynamic_memory.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <string>

#include "ddl/core/error.h"

namespace ddl::dynamics {

void DynamicMemoryConfig::validate() const {
  auto fail = [](const char* key, const std::string& what) {
    throw ConfigError::for_key(std::string("dynamic.memory.") + key, what);
  };
  if (max_age_frames < 1) fail("max_age_frames", "must be >= 1");
  if (sample_stride_px < 1 || sample_stride_px > 32) fail("sample_stride_px", "must be in 1..32");
  if (!(depth_tolerance_m > 0)) fail("depth_tolerance_m", "must be > 0");
  if (!(depth_tolerance_quadratic >= 0)) fail("depth_tolerance_quadratic", "must be >= 0");
  // 0 is "no depth" in a depth image: a minimum of 0 would take holes for measurements.
  if (!(min_depth_m > 0)) fail("min_depth_m", "must be > 0");
  if (!(max_depth_m > min_depth_m)) fail("max_depth_m", "must exceed min_depth_m");
  if (erode_px < 0 || erode_px > 32) fail("erode_px", "must be in 0..32");
  if (max_splat_radius_px < 0 || max_splat_radius_px > 32)
    fail("max_splat_radius_px", "must be in 0..32");
  if (recall_band_px < 0) fail("recall_band_px", "must be >= 0");
  if (static_views < 0 || static_views > 30) fail("static_views", "must be in 0..30");
  if (colour_tolerance > 765) fail("colour_tolerance", "must be <= 765 (negative = off)");
}

DynamicMemory::DynamicMemory(const DynamicMemoryConfig& config, const camera::PinholeCamera& camera)
    : config_(config), camera_(camera) {}

std::size_t DynamicMemory::remembered_points() const {
  std::size_t n = 0;
  for (const Snapshot& s : snapshots_) n += s.points.size();
  return n;
}

void DynamicMemory::forget_before(std::size_t frame_index) {
  const auto max_age = static_cast<std::size_t>(config_.max_age_frames);
  while (!snapshots_.empty() && (snapshots_.front().frame_index > frame_index ||
                                 frame_index - snapshots_.front().frame_index > max_age)) {
    snapshots_.pop_front();
  }
}

void DynamicMemory::add_static_view(const SE3& T_w_c, const cv::Mat& depth_m,
                                    const cv::Mat& dynamic_mask) {
  if (config_.static_views == 0) return;
  CV_Assert(depth_m.type() == CV_32FC1);
  CV_Assert(dynamic_mask.empty() ||
            (dynamic_mask.type() == CV_8UC1 && dynamic_mask.size() == depth_m.size()));
  static_views_.push_back({T_w_c.inverse(), depth_m, dynamic_mask});
  while (static_views_.size() > static_cast<std::size_t>(config_.static_views)) {
    static_views_.pop_front();
  }
}

void DynamicMemory::move_world(const SE3& T_new_old) {
  const Mat3d R = T_new_old.rotation();
  const Vec3d& t = T_new_old.translation();
  for (Snapshot& snapshot : snapshots_) {
    for (Point& point : snapshot.points) {
      const Vec3d p = R * Vec3d(point.x, point.y, point.z) + t;
      point.x = static_cast<float>(p.x());
      point.y = static_cast<float>(p.y());
      point.z = static_cast<float>(p.z());
    }
  }
  const SE3 T_old_new = T_new_old.inverse();
  for (StaticView& view : static_views_) view.T_c_w = view.T_c_w * T_old_new;
}

bool DynamicMemory::seen_as_static(const Vec3d& p_w) const {
  for (const StaticView& view : static_views_) {
    const Vec3d p_c = view.T_c_w * p_w;
    const double z = p_c.z();
    if (!(z >= config_.min_depth_m && z <= config_.max_depth_m)) continue;
    const Vec2d uv = camera_.project(p_c);
    if (!camera_.in_image(uv)) continue;
    const int u = static_cast<int>(std::lround(uv.x()));
    const int v = static_cast<int>(std::lround(uv.y()));
    if (!view.dynamic_mask.empty() && view.dynamic_mask.at<std::uint8_t>(v, u) != 0) continue;
    const float d = view.depth_m.at<float>(v, u);
    if (d > 0.0f && std::abs(d - z) <= config_.tolerance_at(z)) return true;
  }
  return false;
}

void DynamicMemory::remember(std::size_t frame_index, const SE3& T_w_c, const cv::Mat& mask,
                             const cv::Mat& depth_m, const cv::Mat& bgr) {
  if (mask.empty()) return;
  CV_Assert(mask.type() == CV_8UC1 && depth_m.type() == CV_32FC1 && mask.size() == depth_m.size());
  const bool colour = !bgr.empty();
  CV_Assert(!colour || (bgr.type() == CV_8UC3 && bgr.size() == mask.size()));
  cv::Mat core;  // a new buffer: the caller's mask is published to other stages
  if (config_.erode_px > 0) {
    const int k = 2 * config_.erode_px + 1;
    cv::erode(mask, core, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
  } else {
    core = mask;
  }
  Snapshot snapshot;
  snapshot.frame_index = frame_index;
  const int stride = config_.sample_stride_px;
  const Mat3d R = T_w_c.rotation();
  const Vec3d& t = T_w_c.translation();
  for (int v = stride / 2; v < mask.rows; v += stride) {
    const auto* m = core.ptr<std::uint8_t>(v);
    const auto* d = depth_m.ptr<float>(v);
    for (int u = stride / 2; u < mask.cols; u += stride) {
      if (m[u] == 0) continue;
      const double z = d[u];
      if (!(z >= config_.min_depth_m && z <= config_.max_depth_m)) continue;
      const Vec3d p_w = R * camera_.unproject(u, v, z) + t;
      if (seen_as_static(p_w)) continue;
      const cv::Vec3b c = colour ? bgr.at<cv::Vec3b>(v, u) : cv::Vec3b();
      snapshot.points.push_back(
          {static_cast<float>(p_w.x()), static_cast<float>(p_w.y()), static_cast<float>(p_w.z()),
           static_cast<float>(0.5 * stride * z / camera_.fx), c[0], c[1], c[2], colour});
    }
  }
  if (!snapshots_.empty() && snapshots_.back().frame_index >= frame_index) snapshots_.clear();
  forget_before(frame_index);
  snapshots_.push_back(std::move(snapshot));
}

bool DynamicMemory::colour_still_there(const Point& point, int u0, int v0,
                                       const cv::Mat& bgr) const {
  if (config_.colour_tolerance < 0 || bgr.empty() || !point.has_colour) return true;
  // A point just outside the image (its square reaches in) is compared at the nearest pixels
  // inside: the window was empty and such points were all rejected (review, stop 26).
  u0 = std::clamp(u0, 0, bgr.cols - 1);
  v0 = std::clamp(v0, 0, bgr.rows - 1);
  for (int v = std::max(0, v0 - 1); v <= std::min(bgr.rows - 1, v0 + 1); ++v) {
    const auto* row = bgr.ptr<cv::Vec3b>(v);
    for (int u = std::max(0, u0 - 1); u <= std::min(bgr.cols - 1, u0 + 1); ++u) {
      const cv::Vec3b& c = row[u];
      const int difference =
          std::abs(c[0] - point.b) + std::abs(c[1] - point.g) + std::abs(c[2] - point.r);
      if (difference <= config_.colour_tolerance) return true;
    }
  }
  return false;
}

cv::Mat DynamicMemory::recall(std::size_t frame_index, const SE3& T_c_w, const cv::Mat& depth_m,
                              const cv::Mat& bgr, DynamicMemoryStats* stats) {
  DynamicMemoryStats local;
  DynamicMemoryStats& s = stats ? *stats : local;
  s = {};
  forget_before(frame_index);
  if (snapshots_.empty()) return {};
  CV_Assert(depth_m.type() == CV_32FC1);
  CV_Assert(bgr.empty() || (bgr.type() == CV_8UC3 && bgr.size() == depth_m.size()));
  cv::Mat out = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  const Mat3d R = T_c_w.rotation();
  const Vec3d& t = T_c_w.translation();
  for (const Snapshot& snapshot : snapshots_) {
    for (const Point& point : snapshot.points) {
      const Vec3d p_c = R * Vec3d(point.x, point.y, point.z) + t;
      const double z = p_c.z();
      if (!(z >= config_.min_depth_m && z <= config_.max_depth_m)) continue;
      const Vec2d uv = camera_.project(p_c);
      const int u0 = static_cast<int>(std::lround(uv.x()));
      const int v0 = static_cast<int>(std::lround(uv.y()));
      // The square the sample stood for in its own frame, seen at the new distance.
      const int r = std::min(config_.max_splat_radius_px,
                             static_cast<int>(std::ceil(point.reach_m * camera_.fx / z)));
      if (u0 + r < 0 || v0 + r < 0 || u0 - r >= depth_m.cols || v0 - r >= depth_m.rows) continue;
      if (config_.recall_band_px > 0 && camera_.in_image(uv, config_.recall_band_px)) continue;
      ++s.points_projected;
      if (!colour_still_there(point, u0, v0, bgr)) {
        ++s.points_colour_rejected;
        continue;
      }
      const float tolerance = static_cast<float>(config_.tolerance_at(z));
      const float zf = static_cast<float>(z);
      for (int v = std::max(0, v0 - r); v <= std::min(depth_m.rows - 1, v0 + r); ++v) {
        const auto* d = depth_m.ptr<float>(v);
        auto* o = out.ptr<std::uint8_t>(v);
        for (int u = std::max(0, u0 - r); u <= std::min(depth_m.cols - 1, u0 + r); ++u) {
          if (d[u] > 0.0f && std::abs(d[u] - zf) <= tolerance) o[u] = 255;
        }
      }
    }
  }
  s.pixels_marked = cv::countNonZero(out);
  return out;
}

}  // namespace ddl::dynamics
