#include "ddl/dynamics/geometry_check.h"

#include <fmt/format.h>

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <queue>

#include "ddl/core/error.h"

namespace ddl::dynamics {

void GeometryCheckConfig::validate() const {
  auto fail = [](const char* key, const std::string& what) {
    throw ConfigError::for_key(std::string("dynamics.") + key, what);
  };
  if (max_reference_keyframes < 1) fail("max_reference_keyframes", "must be >= 1");
  if (!(max_parallax_deg > 0 && max_parallax_deg <= 180))
    fail("max_parallax_deg", "must be in (0, 180]");
  if (!(depth_threshold_m > 0)) fail("depth_threshold_m", "must be > 0");
  if (!(depth_threshold_quadratic >= 0)) fail("depth_threshold_quadratic", "must be >= 0");
  if (!(min_depth_m >= 0 && max_depth_m > min_depth_m))
    fail("max_depth_m", "must exceed min_depth_m");
  if (max_points_per_keyframe < 1) fail("max_points_per_keyframe", "must be >= 1");
  if (min_seed_support < 1) fail("min_seed_support", "must be >= 1");
  if (!(region_depth_band_m > 0)) fail("region_depth_band_m", "must be > 0");
  if (region_max_radius_px < 1) fail("region_max_radius_px", "must be >= 1");
  if (dilation_px < 0) fail("dilation_px", "must be >= 0");
  if (!(occluder_agreement_m >= 0)) fail("occluder_agreement_m", "must be >= 0");
}

cv::Mat grow_regions(const cv::Mat& depth_m, const std::vector<cv::Point>& seeds,
                     const GeometryCheckConfig& config) {
  cv::Mat region_id(depth_m.size(), CV_32SC1, cv::Scalar(0));
  cv::Mat out = cv::Mat::zeros(depth_m.size(), CV_8UC1);
  const int r2_max = config.region_max_radius_px * config.region_max_radius_px;
  const float band = static_cast<float>(config.region_depth_band_m);
  std::vector<int> support;  // seeds per region, index = region id - 1
  std::vector<std::vector<cv::Point>> regions;
  std::vector<cv::Point> stack;
  for (const cv::Point& seed : seeds) {
    const int existing = region_id.at<int>(seed);
    if (existing > 0) {
      ++support[static_cast<std::size_t>(existing - 1)];
      continue;
    }
    const float d0 = depth_m.at<float>(seed);
    if (d0 <= 0.0f) continue;
    const int id = static_cast<int>(regions.size()) + 1;
    regions.emplace_back();
    support.push_back(1);
    stack.clear();
    stack.push_back(seed);
    region_id.at<int>(seed) = id;
    while (!stack.empty()) {
      const cv::Point p = stack.back();
      stack.pop_back();
      regions.back().push_back(p);
      static constexpr int kDx[4] = {1, -1, 0, 0};
      static constexpr int kDy[4] = {0, 0, 1, -1};
      for (int k = 0; k < 4; ++k) {
        const cv::Point q(p.x + kDx[k], p.y + kDy[k]);
        if (q.x < 0 || q.y < 0 || q.x >= depth_m.cols || q.y >= depth_m.rows) continue;
        if (region_id.at<int>(q) != 0) continue;
        const int dx = q.x - seed.x;
        const int dy = q.y - seed.y;
        if (dx * dx + dy * dy > r2_max) continue;
        const float d = depth_m.at<float>(q);
        if (d <= 0.0f || std::abs(d - d0) > band) continue;
        region_id.at<int>(q) = id;
        stack.push_back(q);
      }
    }
  }
  for (std::size_t i = 0; i < regions.size(); ++i) {
    if (support[i] < config.min_seed_support) continue;
    for (const cv::Point& p : regions[i]) out.at<std::uint8_t>(p) = 255;
  }
  return out;
}

namespace {

// True when the surface measured at current pixel (u, v) was also there when the reference
// keyframe looked: then what hides the reference's point is static structure.
bool occluder_seen_by_reference(const ReferenceView& ref, const SE3& T_w_cur,
                                const camera::PinholeCamera& camera, int u, int v, double z_meas,
                                double tau, const GeometryCheckConfig& config) {
  const Vec3d p_w = T_w_cur * camera.unproject(u, v, z_meas);
  const Vec3d p_ref = ref.T_w_c.inverse() * p_w;
  if (p_ref.z() <= config.min_depth_m) return false;
  const Vec2d uv = camera.project(p_ref);
  const int ur = static_cast<int>(std::lround(uv.x()));
  const int vr = static_cast<int>(std::lround(uv.y()));
  const cv::Mat& d = ref.depth_image_m;
  if (ur < 0 || vr < 0 || ur >= d.cols || vr >= d.rows) return false;
  const float z_ref = d.at<float>(vr, ur);
  if (z_ref <= 0.0f) return false;
  return std::abs(z_ref - p_ref.z()) < config.occluder_agreement_m + 0.5 * tau;
}

}  // namespace

cv::Mat geometry_dynamic_mask(const cv::Mat& depth_m, const SE3& T_c_w,
                              const std::vector<ReferenceView>& references,
                              const camera::PinholeCamera& camera,
                              const GeometryCheckConfig& config, GeometryCheckStats* stats) {
  if (depth_m.type() != CV_32FC1) throw Error("geometry check: depth must be CV_32FC1 metres");
  GeometryCheckStats local;
  const double cos_max_parallax = std::cos(config.max_parallax_deg * M_PI / 180.0);
  const SE3 T_w_c = T_c_w.inverse();
  const Vec3d center_cur_w = T_w_c.translation();
  std::vector<cv::Point> seeds;
  const int limit =
      std::min<int>(config.max_reference_keyframes, static_cast<int>(references.size()));
  for (int r = 0; r < limit; ++r) {
    const ReferenceView& ref = references[static_cast<std::size_t>(r)];
    const std::size_t n = ref.pixels.size();
    const std::size_t step =
        std::max<std::size_t>(1, n / static_cast<std::size_t>(config.max_points_per_keyframe));
    const Vec3d center_ref_w = ref.T_w_c.translation();
    const SE3 T_cur_ref = T_c_w * ref.T_w_c;
    for (std::size_t i = 0; i < n; i += step) {
      const double z_ref = ref.depth_m[i];
      if (z_ref < config.min_depth_m || z_ref > config.max_depth_m) continue;
      const Vec3d p_ref = camera.unproject(ref.pixels[i].x, ref.pixels[i].y, z_ref);
      const Vec3d p_cur = T_cur_ref * p_ref;
      if (p_cur.z() <= config.min_depth_m) continue;
      const Vec2d uv = camera.project(p_cur);
      const int u = static_cast<int>(std::lround(uv.x()));
      const int v = static_cast<int>(std::lround(uv.y()));
      if (u < 0 || v < 0 || u >= depth_m.cols || v >= depth_m.rows) continue;
      ++local.points_tested;
      // Parallax between the rays from both camera centres to the point.
      const Vec3d p_w = ref.T_w_c * p_ref;
      const Vec3d ray_ref = (p_w - center_ref_w).normalized();
      const Vec3d ray_cur = (p_w - center_cur_w).normalized();
      if (ray_ref.dot(ray_cur) < cos_max_parallax) {
        ++local.points_skipped_parallax;
        continue;
      }
      const float z_meas = depth_m.at<float>(v, u);
      if (z_meas < config.min_depth_m || z_meas > config.max_depth_m) continue;
      const double z_proj = p_cur.z();
      const double tau =
          config.depth_threshold_m + config.depth_threshold_quadratic * z_proj * z_proj;
      if (z_proj - z_meas <= tau) continue;
      if (!ref.depth_image_m.empty() &&
          occluder_seen_by_reference(ref, T_w_c, camera, u, v, z_meas, tau, config)) {
        ++local.points_rejected_static_occluder;
        continue;
      }
      ++local.points_dynamic;
      seeds.emplace_back(u, v);
    }
  }
  cv::Mat mask = grow_regions(depth_m, seeds, config);
  if (config.dilation_px > 0 && !seeds.empty()) {
    const int k = 2 * config.dilation_px + 1;
    cv::dilate(mask, mask, cv::getStructuringElement(cv::MORPH_ELLIPSE, {k, k}));
  }
  if (stats != nullptr) *stats = local;
  return mask;
}

}  // namespace ddl::dynamics
