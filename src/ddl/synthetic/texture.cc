#include "ddl/synthetic/texture.h"

#include <opencv2/imgproc.hpp>

#include "ddl/core/error.h"

namespace ddl::synthetic {

Texture make_texture(const cv::Mat& bgr, const cv::Mat& alpha, std::string source) {
  if (bgr.empty() || bgr.type() != CV_8UC3) {
    throw Error(fmt::format("texture '{}': expected a non-empty 8-bit BGR image", source));
  }
  if (!alpha.empty() && (alpha.type() != CV_8UC1 || alpha.size() != bgr.size())) {
    throw Error(fmt::format("texture '{}': alpha must be 8-bit, one channel, {}x{}", source,
                            bgr.cols, bgr.rows));
  }
  Texture tex;
  tex.source = std::move(source);
  tex.color.push_back(bgr.clone());
  if (!alpha.empty()) tex.alpha.push_back(alpha.clone());
  while (tex.color.back().cols > 4 && tex.color.back().rows > 4) {
    const cv::Mat& prev = tex.color.back();
    const cv::Size half((prev.cols + 1) / 2, (prev.rows + 1) / 2);
    cv::Mat next;
    cv::resize(prev, next, half, 0, 0, cv::INTER_AREA);
    tex.color.push_back(next);
    if (!tex.alpha.empty()) {
      cv::Mat next_alpha;
      cv::resize(tex.alpha.back(), next_alpha, half, 0, 0, cv::INTER_AREA);
      tex.alpha.push_back(next_alpha);
    }
  }
  return tex;
}

}  // namespace ddl::synthetic
