#pragma once
// Base of the faster stand-ins for OpenCV dnn layers (segmentation/fast_layers.h): a layer that
// computes the cases it knows itself, on the CPU target only, and hands every other one to
// OpenCV's own layer of the same type, created from the same parameters. The output shapes,
// finalize(), quantization (Net::quantize) and the FLOP count are OpenCV's layer's; the network's
// target is passed on to it (OpenCL FP16 blobs are converted by it).
// Thread-safety: one instance serves one network, as OpenCV's own layers do.

#include <opencv2/dnn.hpp>
#include <vector>

namespace ddl::segmentation {

class FallbackLayer : public cv::dnn::Layer {
 public:
  FallbackLayer(const cv::dnn::LayerParams& params, cv::Ptr<cv::dnn::Layer> fallback);

  bool getMemoryShapes(const std::vector<cv::dnn::MatShape>& inputs, int required_outputs,
                       std::vector<cv::dnn::MatShape>& outputs,
                       std::vector<cv::dnn::MatShape>& internals) const final;
  void finalize(cv::InputArrayOfArrays inputs, cv::OutputArrayOfArrays outputs) final;
  void forward(cv::InputArrayOfArrays inputs, cv::OutputArrayOfArrays outputs,
               cv::OutputArrayOfArrays internals) final;
  bool tryQuantize(const std::vector<std::vector<float>>& scales,
                   const std::vector<std::vector<int>>& zeropoints,
                   cv::dnn::LayerParams& params) final;
  int64 getFLOPS(const std::vector<cv::dnn::MatShape>& inputs,
                 const std::vector<cv::dnn::MatShape>& outputs) const final;

  /// Whether the last forward() computed the output itself (for tests).
  bool used_own_path() const { return used_own_path_; }

 protected:
  /// Writes the output of the (first) input into `out` (allocated by the network) and returns true,
  /// or returns false without writing when OpenCV's layer is to compute it.
  virtual bool compute(const cv::Mat& in, cv::Mat& out) const = 0;

 private:
  cv::Ptr<cv::dnn::Layer> fallback_;
  bool used_own_path_ = false;
};

}  // namespace ddl::segmentation
