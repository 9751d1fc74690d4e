#pragma once
// Base of the faster stand-ins for OpenCV dnn layers (segmentation/fast_layers.h): a layer that
// computes the cases it knows itself and hands every other one to OpenCV's own layer of the same
// type, created from the same parameters (which also gives the output shapes).
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
