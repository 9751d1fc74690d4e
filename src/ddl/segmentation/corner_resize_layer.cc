#include "ddl/segmentation/corner_resize_layer.h"

#include <algorithm>
#include <opencv2/dnn/all_layers.hpp>
#include <string>

namespace ddl::segmentation {

CornerResizeLayer::CornerResizeLayer(const cv::dnn::LayerParams& params)
    : FallbackLayer(params, cv::dnn::ResizeLayer::create(params)) {
  const std::string interpolation = params.get<std::string>("interpolation", "");
  bilinear_aligned_ = interpolation == "bilinear" && params.get<bool>("align_corners", false) &&
                      !params.get<bool>("half_pixel_centers", false);
}

cv::Ptr<cv::dnn::Layer> CornerResizeLayer::create(cv::dnn::LayerParams& params) {
  return cv::makePtr<CornerResizeLayer>(params);
}

bool CornerResizeLayer::compute(const cv::Mat& in, cv::Mat& out) const {
  if (!bilinear_aligned_) return false;
  if (in.dims != 4 || out.dims != 4 || in.type() != CV_32F || out.type() != CV_32F ||
      !in.isContinuous() || !out.isContinuous() || in.size[0] != out.size[0] ||
      in.size[1] != out.size[1] || in.data == out.data) {
    return false;
  }
  const int in_h = in.size[2], in_w = in.size[3];
  const int out_h = out.size[2], out_w = out.size[3];
  if (out_h == in_h && out_w == in_w) return false;  // OpenCV's layer leaves that to the net
  // The scales as OpenCV computes them for aligned corners.
  const float scale_h = out_h > 1 ? static_cast<float>(in_h - 1) / (out_h - 1) : 0.f;
  const float scale_w = out_w > 1 ? static_cast<float>(in_w - 1) / (out_w - 1) : 0.f;
  std::vector<int> x0(static_cast<std::size_t>(out_w)), x1(x0.size());
  std::vector<float> fx(x0.size());
  for (int x = 0; x < out_w; ++x) {
    const float input_x = x * scale_w;
    x0[x] = static_cast<int>(input_x);
    x1[x] = std::min(x0[x] + 1, in_w - 1);
    fx[x] = input_x - x0[x];
  }
  const int planes = in.size[0] * in.size[1];
  const std::size_t in_plane = static_cast<std::size_t>(in_h) * in_w;
  const std::size_t out_plane = static_cast<std::size_t>(out_h) * out_w;
  for (int p = 0; p < planes; ++p) {
    const float* src = in.ptr<float>() + p * in_plane;
    float* dst = out.ptr<float>() + p * out_plane;
    for (int y = 0; y < out_h; ++y) {
      const float input_y = y * scale_h;
      const int y0 = static_cast<int>(input_y);
      const float fy = input_y - y0;
      const float* r0 = src + static_cast<std::size_t>(y0) * in_w;
      const float* r1 = src + static_cast<std::size_t>(std::min(y0 + 1, in_h - 1)) * in_w;
      float* row = dst + static_cast<std::size_t>(y) * out_w;
      for (int x = 0; x < out_w; ++x) {
        const int a = x0[x], b = x1[x];
        // OpenCV's expression, term for term.
        row[x] = r0[a] + fy * (r1[a] - r0[a]) +
                 fx[x] * (r0[b] - r0[a] + fy * (r1[b] - r0[b] - r1[a] + r0[a]));
      }
    }
  }
  return true;
}

}  // namespace ddl::segmentation
