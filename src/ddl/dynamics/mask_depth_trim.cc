#include "ddl/dynamics/mask_depth_trim.h"

#include <algorithm>
#include <limits>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "ddl/core/error.h"

namespace ddl::dynamics {

void DepthTrimConfig::validate() const {
  auto fail = [](const char* key, const std::string& what) {
    throw ConfigError::for_key(std::string("dynamic.depth_trim.") + key, what);
  };
  if (!(band_m > 0)) fail("band_m", "must be > 0");
  if (core_erode_px < 0 || core_erode_px > 32) fail("core_erode_px", "must be in 0..32");
  if (min_core_samples < 1) fail("min_core_samples", "must be >= 1");
}

namespace {

float median_of(std::vector<float>& values) {
  const auto mid = values.begin() + static_cast<std::ptrdiff_t>(values.size() / 2);
  std::nth_element(values.begin(), mid, values.end());
  return *mid;
}

}  // namespace

cv::Mat trim_mask_by_depth(const cv::Mat& mask, const cv::Mat& depth_m,
                           const DepthTrimConfig& config) {
  if (mask.empty()) return {};
  CV_Assert(mask.type() == CV_8UC1 && depth_m.type() == CV_32FC1 && mask.size() == depth_m.size());
  cv::Mat labels;
  const int n = cv::connectedComponents(mask, labels, 8, CV_32S);
  cv::Mat out = mask.clone();
  if (n <= 1) return out;
  cv::Mat core;
  if (config.core_erode_px > 0) {
    const int k = 2 * config.core_erode_px + 1;
    cv::erode(mask, core, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
  } else {
    core = mask;
  }
  std::vector<std::vector<float>> core_depths(static_cast<std::size_t>(n));
  std::vector<std::vector<float>> all_depths(static_cast<std::size_t>(n));
  for (int v = 0; v < mask.rows; ++v) {
    const int* l = labels.ptr<int>(v);
    const float* d = depth_m.ptr<float>(v);
    const std::uint8_t* c = core.ptr<std::uint8_t>(v);
    for (int u = 0; u < mask.cols; ++u) {
      if (l[u] == 0 || !(d[u] > 0.0f)) continue;
      all_depths[static_cast<std::size_t>(l[u])].push_back(d[u]);
      if (c[u] != 0) core_depths[static_cast<std::size_t>(l[u])].push_back(d[u]);
    }
  }
  // Deepest depth kept per region; infinity = keep the whole region (no depth to judge by).
  std::vector<float> limit(static_cast<std::size_t>(n), std::numeric_limits<float>::infinity());
  for (std::size_t i = 1; i < limit.size(); ++i) {
    std::vector<float>& samples = static_cast<int>(core_depths[i].size()) >= config.min_core_samples
                                      ? core_depths[i]
                                      : all_depths[i];
    if (samples.empty()) continue;
    limit[i] = median_of(samples) + static_cast<float>(config.band_m);
  }
  for (int v = 0; v < mask.rows; ++v) {
    const int* l = labels.ptr<int>(v);
    const float* d = depth_m.ptr<float>(v);
    std::uint8_t* o = out.ptr<std::uint8_t>(v);
    for (int u = 0; u < mask.cols; ++u) {
      if (l[u] != 0 && d[u] > limit[static_cast<std::size_t>(l[u])]) o[u] = 0;
    }
  }
  return out;
}

}  // namespace ddl::dynamics
