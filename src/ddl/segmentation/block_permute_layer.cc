#include "ddl/segmentation/block_permute_layer.h"

#include <cstring>
#include <opencv2/dnn/all_layers.hpp>

namespace ddl::segmentation {

BlockPermuteLayer::BlockPermuteLayer(const cv::dnn::LayerParams& params)
    : FallbackLayer(params, cv::dnn::PermuteLayer::create(params)) {
  if (params.has("order")) {
    const cv::dnn::DictValue& order = params.get("order");
    for (int i = 0; i < order.size(); ++i) order_.push_back(order.get<int>(i));
  }
}

cv::Ptr<cv::dnn::Layer> BlockPermuteLayer::create(cv::dnn::LayerParams& params) {
  return cv::makePtr<BlockPermuteLayer>(params);
}

bool BlockPermuteLayer::compute(const cv::Mat& in, cv::Mat& out) const {
  const int dims = in.dims;
  if (in.type() != CV_32F || out.type() != CV_32F || !in.isContinuous() || !out.isContinuous() ||
      static_cast<int>(order_.size()) != dims || out.dims != dims) {
    return false;
  }
  // The innermost dimensions that stay in place form the block.
  int first_kept = dims;
  while (first_kept > 0 && order_[first_kept - 1] == first_kept - 1) --first_kept;
  std::size_t block = 1;
  for (int d = first_kept; d < dims; ++d) block *= static_cast<std::size_t>(in.size[d]);
  if (block < kMinBlockElements) return false;
  if (in.data == out.data) return first_kept == 0;  // in place: only the identity needs nothing
  for (int d = 0; d < dims; ++d) {
    if (out.size[d] != in.size[order_[d]]) return false;
  }
  // Input strides in elements; output blocks are written in order.
  std::vector<std::size_t> in_stride(static_cast<std::size_t>(dims), 1);
  for (int d = dims - 2; d >= 0; --d) {
    in_stride[d] = in_stride[d + 1] * static_cast<std::size_t>(in.size[d + 1]);
  }
  const float* src = in.ptr<float>();
  float* dst = out.ptr<float>();
  std::vector<int> index(static_cast<std::size_t>(first_kept), 0);  // output outer index
  std::size_t blocks = 1;
  for (int d = 0; d < first_kept; ++d) blocks *= static_cast<std::size_t>(out.size[d]);
  for (std::size_t b = 0; b < blocks; ++b) {
    std::size_t offset = 0;
    for (int d = 0; d < first_kept; ++d) {
      offset += static_cast<std::size_t>(index[d]) * in_stride[order_[d]];
    }
    std::memcpy(dst + b * block, src + offset, block * sizeof(float));
    for (int d = first_kept - 1; d >= 0; --d) {  // next output outer index
      if (++index[d] < out.size[d]) break;
      index[d] = 0;
    }
  }
  return true;
}

}  // namespace ddl::segmentation
