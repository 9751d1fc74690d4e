#include "ddl/synthetic/depth_model.h"

#include <algorithm>
#include <cmath>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgproc.hpp>

#include "ddl/core/error.h"
#include "ddl/synthetic/random.h"

namespace ddl::synthetic {

void DepthNoiseConfig::validate() const {
  auto require = [](bool ok, const char* key, double value, const char* what) {
    if (!ok) throw ConfigError::for_key(key, fmt::format("{} (got {})", what, value));
  };
  require(min_range_m >= 0 && std::isfinite(min_range_m), "depth.min_range_m", min_range_m,
          "must be >= 0");
  require(max_range_m > min_range_m && max_range_m < 13.0, "depth.max_range_m", max_range_m,
          "must be above min_range_m and below 13 m (16-bit range at 5000/m)");
  require(max_incidence_deg > 0 && max_incidence_deg <= 90, "depth.max_incidence_deg",
          max_incidence_deg, "must be in (0, 90]");
  require(sigma_base_m >= 0, "depth.sigma_base_m", sigma_base_m, "must be >= 0");
  require(sigma_quadratic >= 0, "depth.sigma_quadratic", sigma_quadratic, "must be >= 0");
  require(sigma_angular >= 0, "depth.sigma_angular", sigma_angular, "must be >= 0");
  require(disparity_fb_px_m > 0, "depth.disparity_fb_px_m", disparity_fb_px_m, "must be > 0");
  require(disparity_subpixel >= 0, "depth.disparity_subpixel", disparity_subpixel, "must be >= 0");
  require(edge_jump_m > 0, "depth.edge_jump_m", edge_jump_m, "must be > 0");
  require(edge_jump_relative >= 0, "depth.edge_jump_relative", edge_jump_relative, "must be >= 0");
  require(edge_extra_probability >= 0 && edge_extra_probability <= 1,
          "depth.edge_extra_probability", edge_extra_probability, "must be in [0, 1]");
}

cv::Mat apply_depth_model(const cv::Mat& depth_m, const cv::Mat& cos_incidence,
                          const DepthNoiseConfig& config, double depth_factor, std::uint64_t seed,
                          std::uint64_t frame) {
  CV_Assert(depth_m.type() == CV_32FC1 && cos_incidence.type() == CV_32FC1 &&
            depth_m.size() == cos_incidence.size());
  const int width = depth_m.cols;
  cv::Mat raw(depth_m.size(), CV_16UC1, cv::Scalar(0));
  if (!config.enabled) {
    depth_m.convertTo(raw, CV_16UC1, depth_factor);  // rounds to nearest, saturates
    return raw;
  }
  // Neighbourhood extremes for the edge test (pixels outside the image are ignored; an empty
  // neighbour has depth 0, so the pixel next to it is on the "far side" and drops out).
  cv::Mat min3, max3, min5;
  cv::erode(depth_m, min3, cv::Mat::ones(3, 3, CV_8U));
  cv::dilate(depth_m, max3, cv::Mat::ones(3, 3, CV_8U));
  cv::erode(depth_m, min5, cv::Mat::ones(5, 5, CV_8U));
  const std::uint64_t frame_key = hash3(seed, frame, 0xdeb7U);
  const float min_cos = static_cast<float>(std::cos(config.max_incidence_deg * M_PI / 180.0));
  const float min_range = static_cast<float>(config.min_range_m);
  const float max_range = static_cast<float>(config.max_range_m);
  const double k = config.disparity_fb_px_m * config.disparity_subpixel;
  const auto extra_threshold =
      static_cast<std::uint64_t>(config.edge_extra_probability * 4294967296.0);
  cv::parallel_for_(cv::Range(0, depth_m.rows), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      const float* z_row = depth_m.ptr<float>(v);
      const float* c_row = cos_incidence.ptr<float>(v);
      const float* min3_row = min3.ptr<float>(v);
      const float* max3_row = max3.ptr<float>(v);
      const float* min5_row = min5.ptr<float>(v);
      auto* out = raw.ptr<std::uint16_t>(v);
      for (int u = 0; u < width; ++u) {
        const float z = z_row[u];
        if (!(z > 0.0f) || z < min_range || z > max_range || c_row[u] < min_cos) continue;
        // Depth discontinuities: the far side within 1 px always; on a coin flip also the near
        // side and the far side within 2 px.
        const float jump = static_cast<float>(config.edge_jump_m) +
                           static_cast<float>(config.edge_jump_relative) * z;
        if (z - min3_row[u] > jump) continue;
        const std::uint64_t h = hash2(frame_key, static_cast<std::uint64_t>(v) * width + u);
        const bool wide = (mix64(h) >> 32U) < extra_threshold;
        if (wide && (max3_row[u] - z > jump || z - min5_row[u] > jump)) continue;
        const double theta = std::acos(std::min(1.0f, c_row[u]));
        const double dz = z - config.sigma_offset_m;
        const double lateral = M_PI / 2 - theta;
        const double sigma =
            config.sigma_base_m + config.sigma_quadratic * dz * dz +
            config.sigma_angular / std::sqrt(z) * theta * theta / (lateral * lateral);
        double noisy = z + sigma * gauss_from_hash(h);
        if (k > 0 && noisy > 0) {
          const double disparity_steps = std::nearbyint(k / noisy);
          if (disparity_steps <= 0) continue;
          noisy = k / disparity_steps;
        }
        if (noisy < config.min_range_m || noisy > config.max_range_m) continue;
        out[u] = static_cast<std::uint16_t>(std::min(65535.0, noisy * depth_factor + 0.5));
      }
    }
  });
  return raw;
}

void add_rgb_noise(cv::Mat& bgr, double sigma, std::uint64_t seed, std::uint64_t frame,
                   const cv::Mat& only) {
  if (sigma <= 0) return;
  CV_Assert(bgr.type() == CV_8UC3);
  CV_Assert(only.empty() || (only.type() == CV_8UC1 && only.size() == bgr.size()));
  const std::uint64_t frame_key = hash3(seed, frame, 0xc0104U);
  // Each channel: a triangular variate (sum of two uniforms in [-0.5, 0.5]) of std 1/sqrt(6).
  const float scale = static_cast<float>(sigma * std::sqrt(6.0));
  cv::parallel_for_(cv::Range(0, bgr.rows), [&](const cv::Range& rows) {
    for (int v = rows.start; v < rows.end; ++v) {
      auto* p = bgr.ptr<unsigned char>(v);
      const unsigned char* m = only.empty() ? nullptr : only.ptr<unsigned char>(v);
      for (int u = 0; u < bgr.cols; ++u) {
        if (m != nullptr && m[u] == 0) continue;
        std::uint64_t h = hash2(frame_key, static_cast<std::uint64_t>(v) * bgr.cols + u);
        for (int c = 0; c < 3; ++c) {
          const float a = static_cast<float>(h & 0x3ffU) * (1.0f / 1023.0f);
          const float b = static_cast<float>((h >> 10U) & 0x3ffU) * (1.0f / 1023.0f);
          h >>= 20U;
          const float value = p[3 * u + c] + scale * (a + b - 1.0f) + 0.5f;
          p[3 * u + c] = static_cast<unsigned char>(std::clamp(value, 0.0f, 255.0f));
        }
      }
    }
  });
}

cv::Mat fill_missing_depth_nearest(const cv::Mat& depth_m) {
  if (depth_m.type() != CV_32FC1) throw Error("fill_missing_depth_nearest: expects CV_32FC1");
  const cv::Mat missing = depth_m <= 0.0f;  // distanceTransform: distance to the nearest 0 here
  const auto missing_count = static_cast<std::size_t>(cv::countNonZero(missing));
  if (missing_count == 0 || missing_count == missing.total()) {
    return depth_m.clone();
  }
  cv::Mat distance;
  cv::Mat labels;
  cv::distanceTransform(missing, distance, labels, cv::DIST_L2, cv::DIST_MASK_5,
                        cv::DIST_LABEL_PIXEL);
  // Each valid pixel carries its own label; look up the depth of the label's pixel.
  std::vector<float> depth_of_label(static_cast<std::size_t>(depth_m.total()) + 1, 0.0f);
  for (int v = 0; v < depth_m.rows; ++v) {
    const float* d = depth_m.ptr<float>(v);
    const int* l = labels.ptr<int>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      if (d[u] > 0.0f) depth_of_label[static_cast<std::size_t>(l[u])] = d[u];
    }
  }
  cv::Mat filled = depth_m.clone();
  for (int v = 0; v < depth_m.rows; ++v) {
    float* f = filled.ptr<float>(v);
    const int* l = labels.ptr<int>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      if (f[u] <= 0.0f) f[u] = depth_of_label[static_cast<std::size_t>(l[u])];
    }
  }
  return filled;
}

}  // namespace ddl::synthetic
