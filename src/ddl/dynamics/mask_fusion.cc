#include "ddl/dynamics/mask_fusion.h"

#include <opencv2/imgproc.hpp>

#include "ddl/core/error.h"

namespace ddl::dynamics {

cv::Mat combine_masks(const cv::Mat& cnn_mask, const cv::Mat& geometry_mask) {
  if (cnn_mask.empty()) return geometry_mask;
  if (geometry_mask.empty()) return cnn_mask;
  if (cnn_mask.size() != geometry_mask.size()) throw Error("combine_masks: sizes differ");
  cv::Mat out;
  cv::bitwise_or(cnn_mask, geometry_mask, out);
  return out;
}

cv::Mat feature_exclusion_mask(const cv::Mat& dynamic_mask, int border_px) {
  if (dynamic_mask.empty() || border_px <= 0) return dynamic_mask;
  cv::Mat out;
  const int k = 2 * border_px + 1;
  cv::dilate(dynamic_mask, out, cv::getStructuringElement(cv::MORPH_ELLIPSE, {k, k}));
  return out;
}

MaskScore score_mask(const cv::Mat& predicted, const cv::Mat& truth) {
  if (predicted.size() != truth.size()) throw Error("score_mask: sizes differ");
  MaskScore s;
  cv::Mat p = predicted != 0;
  cv::Mat t = truth != 0;
  cv::Mat both;
  cv::bitwise_and(p, t, both);
  s.true_positive = cv::countNonZero(both);
  s.predicted = cv::countNonZero(p);
  s.truth = cv::countNonZero(t);
  const long uni = s.predicted + s.truth - s.true_positive;
  s.iou = uni > 0 ? static_cast<double>(s.true_positive) / static_cast<double>(uni) : 1.0;
  s.precision = s.predicted > 0 ? static_cast<double>(s.true_positive) / s.predicted : 1.0;
  s.recall = s.truth > 0 ? static_cast<double>(s.true_positive) / s.truth : 1.0;
  return s;
}

}  // namespace ddl::dynamics
