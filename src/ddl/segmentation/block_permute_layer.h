#pragma once
// A faster stand-in for OpenCV dnn's Permute layer (ONNX Transpose) with the same output: when
// the permutation keeps the innermost dimensions in place, it moves whole blocks of them with
// memcpy instead of one element at a time. ESPNetv2's channel shuffles are such permutations
// (order 0 2 1 3 4 on 1 x 5 x 10 x 120 x 160 at the 320x240 input): OpenCV 4.6's generic
// Permute spent about 22 of the network's 106 ms on its 4 shuffles (docs/dynamics.md, "CNN cost").
// Any other case (other element types, blocks of fewer than kMinBlockElements) runs OpenCV's own
// PermuteLayer, created from the same parameters.
//
// Installed by register_fast_layers() (segmentation/fast_layers.h). Thread-safety: one instance
// serves one network, as OpenCV's own layers do.

#include <cstddef>
#include <opencv2/dnn.hpp>
#include <vector>

#include "ddl/segmentation/fallback_layer.h"

namespace ddl::segmentation {

class BlockPermuteLayer final : public FallbackLayer {
 public:
  /// Innermost elements a block needs for the fast path (smaller blocks: OpenCV's layer).
  static constexpr std::size_t kMinBlockElements = 16;

  explicit BlockPermuteLayer(const cv::dnn::LayerParams& params);
  static cv::Ptr<cv::dnn::Layer> create(cv::dnn::LayerParams& params);

 private:
  bool compute(const cv::Mat& in, cv::Mat& out) const override;

  std::vector<int> order_;  // output dimension i is input dimension order_[i]
};

}  // namespace ddl::segmentation
