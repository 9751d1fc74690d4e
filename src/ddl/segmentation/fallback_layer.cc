#include "ddl/segmentation/fallback_layer.h"

#include <utility>

namespace ddl::segmentation {

FallbackLayer::FallbackLayer(const cv::dnn::LayerParams& params, cv::Ptr<cv::dnn::Layer> fallback)
    : Layer(params), fallback_(std::move(fallback)) {}

bool FallbackLayer::getMemoryShapes(const std::vector<cv::dnn::MatShape>& inputs,
                                    int required_outputs, std::vector<cv::dnn::MatShape>& outputs,
                                    std::vector<cv::dnn::MatShape>& internals) const {
  return fallback_->getMemoryShapes(inputs, required_outputs, outputs, internals);
}

void FallbackLayer::finalize(cv::InputArrayOfArrays inputs, cv::OutputArrayOfArrays outputs) {
  fallback_->finalize(inputs, outputs);
}

void FallbackLayer::forward(cv::InputArrayOfArrays inputs, cv::OutputArrayOfArrays outputs,
                            cv::OutputArrayOfArrays internals) {
  // Net sets the target after finalize(); OpenCV's layer needs it to handle FP16 blobs.
  fallback_->preferableTarget = preferableTarget;
  used_own_path_ = false;
  if (preferableTarget == cv::dnn::DNN_TARGET_CPU) {
    std::vector<cv::Mat> in, out;
    inputs.getMatVector(in);
    outputs.getMatVector(out);
    used_own_path_ = !in.empty() && out.size() == 1 && compute(in[0], out[0]);
  }
  if (!used_own_path_) fallback_->forward(inputs, outputs, internals);
}

bool FallbackLayer::tryQuantize(const std::vector<std::vector<float>>& scales,
                                const std::vector<std::vector<int>>& zeropoints,
                                cv::dnn::LayerParams& params) {
  return fallback_->tryQuantize(scales, zeropoints, params);
}

int64 FallbackLayer::getFLOPS(const std::vector<cv::dnn::MatShape>& inputs,
                              const std::vector<cv::dnn::MatShape>& outputs) const {
  return fallback_->getFLOPS(inputs, outputs);
}

}  // namespace ddl::segmentation
