#include "ddl/dynamics/mask_edge_refinement.h"

#include <algorithm>
#include <cmath>
#include <opencv2/imgproc.hpp>
#include <opencv2/ximgproc/edge_filter.hpp>
#include <string>

#include "ddl/core/error.h"

namespace ddl::dynamics {

void EdgeRefinementConfig::validate() const {
  auto fail = [](const char* key, const std::string& what) {
    throw ConfigError::for_key(std::string("dynamic.edge_refinement.") + key, what);
  };
  if (!(scale >= 0.1 && scale <= 1.0)) fail("scale", "must be in 0.1..1");
  if (radius_px < 1 || radius_px > 64) fail("radius_px", "must be in 1..64");
  if (!(eps > 0 && eps <= 1)) fail("eps", "must be in (0, 1]");
  if (!(threshold > 0 && threshold < 1)) fail("threshold", "must be in (0, 1)");
  if (follow_up_passes < 0 || follow_up_passes > 10) fail("follow_up_passes", "must be in 0..10");
  if (keep_core_px < 0 || keep_core_px > 64) fail("keep_core_px", "must be in 0..64");
  if (follow_up_radius_px < 1 || follow_up_radius_px > 64) {
    fail("follow_up_radius_px", "must be in 1..64");
  }
}

cv::Mat refine_mask_edges(const cv::Mat& mask, const cv::Mat& bgr,
                          const EdgeRefinementConfig& config, const cv::Mat& keep) {
  if (mask.empty()) return mask;
  CV_Assert(mask.type() == CV_8UC1 && bgr.type() == CV_8UC3 && mask.size() == bgr.size());
  CV_Assert(keep.empty() || (keep.type() == CV_8UC1 && keep.size() == mask.size()));
  const cv::Rect box = cv::boundingRect(mask);
  if (box.empty()) return mask;
  // Each pass sets pixels only within twice its radius of the mask it starts from (a pixel's
  // output averages the coefficients of the windows around it, which see mask pixels only that
  // far), so the box grown by all passes' reach cuts off nothing a pass on the whole image would
  // set (the reach is counted at full resolution from the unrounded radii: at the default scale
  // it covers the rounded ones). The resampling grid starts at the box's corner, so the rim may
  // differ from a run on the whole image by about one filter pixel (1 / scale px).
  // keep_core_px: the erosion below sees the same neighbours in the ROI as in the whole image.
  const int reach =
      std::max(2 * (config.radius_px + config.follow_up_passes * config.follow_up_radius_px) + 2,
               config.keep_core_px + 1);
  const cv::Rect roi =
      cv::Rect(box.x - reach, box.y - reach, box.width + 2 * reach, box.height + 2 * reach) &
      cv::Rect(0, 0, mask.cols, mask.rows);
  const cv::Size small(std::max(1, static_cast<int>(std::lround(roi.width * config.scale))),
                       std::max(1, static_cast<int>(std::lround(roi.height * config.scale))));
  cv::Mat guide, binary, soft;
  cv::resize(bgr(roi), guide, small, 0, 0, cv::INTER_AREA);
  cv::Mat(mask(roi) != 0).convertTo(binary, CV_32FC1, 1.0 / 255.0);
  cv::resize(binary, soft, small, 0, 0, cv::INTER_AREA);
  const auto scaled = [&](int radius_px) {
    return std::max(1, static_cast<int>(std::lround(radius_px * config.scale)));
  };
  // The guide stays 8-bit: the filter works in its intensity units, so eps is scaled to them.
  const double eps = config.eps * 255.0 * 255.0;
  const cv::Ptr<cv::ximgproc::GuidedFilter> first =
      cv::ximgproc::createGuidedFilter(guide, scaled(config.radius_px), eps);
  cv::Ptr<cv::ximgproc::GuidedFilter> follow_up;
  if (config.follow_up_passes > 0) {
    follow_up = cv::ximgproc::createGuidedFilter(guide, scaled(config.follow_up_radius_px), eps);
  }
  // The passes threshold at the filter's scale; only the last soft mask goes back to full size.
  cv::Mat filtered;
  first->filter(soft, filtered);
  for (int pass = 0; pass < config.follow_up_passes; ++pass) {
    cv::Mat(filtered > config.threshold).convertTo(soft, CV_32FC1, 1.0 / 255.0);
    follow_up->filter(soft, filtered);
  }
  cv::Mat full;
  cv::resize(filtered, full, roi.size(), 0, 0, cv::INTER_LINEAR);
  cv::Mat out = cv::Mat::zeros(mask.size(), CV_8UC1);
  out(roi).setTo(255, full > config.threshold);
  if (config.keep_core_px > 0) {
    // The ROI holds the mask with a margin wider than keep_core_px, or ends at the image border
    // as the whole image does: eroding the ROI is eroding the whole mask.
    const int k = 2 * config.keep_core_px + 1;
    cv::Mat core;
    cv::erode(mask(roi), core, cv::getStructuringElement(cv::MORPH_ELLIPSE, cv::Size(k, k)));
    out(roi).setTo(255, core);
  }
  if (!keep.empty()) out.setTo(255, keep);
  return out;
}

}  // namespace ddl::dynamics
