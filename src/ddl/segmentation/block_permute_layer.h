#pragma once
// A faster stand-in for OpenCV dnn's Permute layer (ONNX Transpose) with the same output: when
// the permutation keeps the innermost dimensions in place, it moves whole blocks of them with
// memcpy instead of one element at a time. ESPNetv2's channel shuffles are such permutations
// (order 0 2 1 3 4 on 1 x 5 x 10 x 120 x 160 at the 320x240 input): OpenCV 4.6's generic
// Permute spent 22 of the network's 106 ms on them (docs/dynamics.md, "CNN cost").
// Any other case (other element types, blocks of fewer than kMinBlockElements) runs OpenCV's own
// PermuteLayer, created from the same parameters.
//
// OpenCV creates layers through a process-wide factory, so the stand-in is installed there once
// per process by register_block_permute_layer() (the only way OpenCV offers to replace a layer).
// Thread-safety: register_block_permute_layer() may be called from any thread; one layer
// instance serves one network, as OpenCV's own layers do.

#include <opencv2/dnn.hpp>
#include <opencv2/dnn/all_layers.hpp>
#include <vector>

namespace ddl::segmentation {

class BlockPermuteLayer final : public cv::dnn::Layer {
 public:
  /// Innermost elements a block needs for the fast path (smaller blocks: OpenCV's layer).
  static constexpr std::size_t kMinBlockElements = 16;

  explicit BlockPermuteLayer(const cv::dnn::LayerParams& params);
  static cv::Ptr<cv::dnn::Layer> create(cv::dnn::LayerParams& params);

  bool getMemoryShapes(const std::vector<cv::dnn::MatShape>& inputs, int required_outputs,
                       std::vector<cv::dnn::MatShape>& outputs,
                       std::vector<cv::dnn::MatShape>& internals) const override;
  void finalize(cv::InputArrayOfArrays inputs, cv::OutputArrayOfArrays outputs) override;
  void forward(cv::InputArrayOfArrays inputs, cv::OutputArrayOfArrays outputs,
               cv::OutputArrayOfArrays internals) override;

  /// Whether the last forward() took the block path (for tests).
  bool used_block_path() const { return used_block_path_; }

 private:
  // Copies `in` into `out` permuted, moving blocks of the dimensions from `first_kept` on.
  bool block_permute(const cv::Mat& in, cv::Mat& out) const;

  std::vector<int> order_;  // output dimension i is input dimension order_[i]
  cv::Ptr<cv::dnn::PermuteLayer> fallback_;
  bool used_block_path_ = false;
};

/// Installs BlockPermuteLayer as the "Permute" layer of networks set up from now on (once per
/// process; later calls do nothing).
void register_block_permute_layer();

}  // namespace ddl::segmentation
