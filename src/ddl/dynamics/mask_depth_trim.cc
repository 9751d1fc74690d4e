#include "ddl/dynamics/mask_depth_trim.h"

#include <opencv2/imgproc.hpp>
#include <string>

#include "ddl/core/error.h"

namespace ddl::dynamics {

void DepthTrimConfig::validate() const {
  auto fail = [](const char* key, const std::string& what) {
    throw ConfigError::for_key(std::string("dynamic.depth_trim.") + key, what);
  };
  if (!(band_m > 0)) fail("band_m", "must be > 0");
  if (rim_px < 1 || rim_px > 64) fail("rim_px", "must be in 1..64");
  if (window_px < 1 || window_px > 128) fail("window_px", "must be in 1..128");
}

cv::Mat trim_mask_by_depth(const cv::Mat& mask, const cv::Mat& depth_m,
                           const DepthTrimConfig& config) {
  if (mask.empty()) return {};
  CV_Assert(mask.type() == CV_8UC1 && depth_m.type() == CV_32FC1 && mask.size() == depth_m.size());
  cv::Mat out = mask.clone();
  // The core: the mask eroded by the rim width, where the spill does not reach.
  cv::Mat core;
  const int k = 2 * config.rim_px + 1;
  cv::erode(mask, core, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
  // Mean depth of the core pixels with depth around every pixel (box sums of depth and count).
  // (core != 0): the mask may be 0/1 as well as 0/255 (non-zero = dynamic).
  cv::Mat core_valid = (core != 0) & (depth_m > 0.0f);
  cv::Mat core_depth = cv::Mat::zeros(depth_m.size(), CV_32FC1);
  depth_m.copyTo(core_depth, core_valid);
  cv::Mat count;
  core_valid.convertTo(count, CV_32FC1, 1.0 / 255.0);
  const cv::Size window(2 * config.window_px + 1, 2 * config.window_px + 1);
  cv::Mat depth_sum, count_sum;
  cv::boxFilter(core_depth, depth_sum, CV_32F, window, cv::Point(-1, -1), false,
                cv::BORDER_CONSTANT);
  cv::boxFilter(count, count_sum, CV_32F, window, cv::Point(-1, -1), false, cv::BORDER_CONSTANT);
  const float band = static_cast<float>(config.band_m);
  for (int v = 0; v < mask.rows; ++v) {
    const std::uint8_t* m = mask.ptr<std::uint8_t>(v);
    const std::uint8_t* c = core.ptr<std::uint8_t>(v);
    const float* d = depth_m.ptr<float>(v);
    const float* ds = depth_sum.ptr<float>(v);
    const float* n = count_sum.ptr<float>(v);
    std::uint8_t* o = out.ptr<std::uint8_t>(v);
    for (int u = 0; u < mask.cols; ++u) {
      // Only the rim is judged, against the core next to it; no core nearby: kept.
      if (m[u] == 0 || c[u] != 0 || !(d[u] > 0.0f) || n[u] < 0.5f) continue;
      if (d[u] > ds[u] / n[u] + band) o[u] = 0;
    }
  }
  return out;
}

}  // namespace ddl::dynamics
