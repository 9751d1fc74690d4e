#pragma once
// A faster stand-in for OpenCV dnn's Resize layer in the one case ESPNetv2 uses, bilinear with
// aligned corners (ONNX Resize, coordinate_transformation_mode = align_corners), with the same
// output bit for bit: OpenCV 4.6 walks the output pixel by pixel and, for each, every channel
// plane (a stride of a whole plane per step); this walks each plane row by row with the
// per-column coordinates computed once, and evaluates the same expression in the same order per
// output value. Its 20 Resize layers took 13 of the network's 106 ms (docs/dynamics.md, "CNN
// cost"). Every other case (nearest, half-pixel centres, other types) runs OpenCV's own layer.
// The file is compiled with -ffp-contract=off, so that no fused multiply-add changes a result.
//
// Installed with BlockPermuteLayer by register_fast_layers() (segmentation/fast_layers.h).
// Thread-safety: one instance serves one network, as OpenCV's own layers do.

#include <opencv2/dnn.hpp>

#include "ddl/segmentation/fallback_layer.h"

namespace ddl::segmentation {

class CornerResizeLayer final : public FallbackLayer {
 public:
  explicit CornerResizeLayer(const cv::dnn::LayerParams& params);
  static cv::Ptr<cv::dnn::Layer> create(cv::dnn::LayerParams& params);

 private:
  bool compute(const cv::Mat& in, cv::Mat& out) const override;

  bool bilinear_aligned_ = false;  // the case this layer computes itself
};

}  // namespace ddl::segmentation
