#include "ddl/eval/mask_metrics.h"

#include <cmath>
#include <opencv2/imgproc.hpp>
#include <stdexcept>

namespace ddl::eval {
namespace {

constexpr double kNaN = std::numeric_limits<double>::quiet_NaN();

double ratio(std::uint64_t numerator, std::uint64_t denominator) {
  return denominator == 0 ? kNaN
                          : static_cast<double>(numerator) / static_cast<double>(denominator);
}

nlohmann::json number(double v) {
  return std::isfinite(v) ? nlohmann::json(v) : nlohmann::json(nullptr);
}

}  // namespace

double MaskCounts::iou() const {
  return ratio(true_positive, true_positive + false_positive + false_negative);
}

MaskCounts& MaskCounts::operator+=(const MaskCounts& other) {
  true_positive += other.true_positive;
  false_positive += other.false_positive;
  false_negative += other.false_negative;
  return *this;
}

MaskCounts count_mask_pixels(const cv::Mat& predicted, const cv::Mat& truth,
                             const cv::Mat& region) {
  if (truth.empty() || truth.type() != CV_8UC1) {
    throw std::invalid_argument("count_mask_pixels: the truth mask must be a non-empty CV_8UC1");
  }
  if (!predicted.empty() && predicted.type() != CV_8UC1) {
    throw std::invalid_argument("count_mask_pixels: the predicted mask must be CV_8UC1");
  }
  if (!region.empty() && (region.type() != CV_8UC1 || region.size() != truth.size())) {
    throw std::invalid_argument(
        "count_mask_pixels: the region must be CV_8UC1 of the truth's size");
  }
  cv::Mat prediction = predicted;
  if (!prediction.empty() && prediction.size() != truth.size()) {
    cv::resize(predicted, prediction, truth.size(), 0, 0, cv::INTER_NEAREST);
  }
  MaskCounts counts;
  for (int y = 0; y < truth.rows; ++y) {
    const std::uint8_t* t = truth.ptr<std::uint8_t>(y);
    const std::uint8_t* p = prediction.empty() ? nullptr : prediction.ptr<std::uint8_t>(y);
    const std::uint8_t* r = region.empty() ? nullptr : region.ptr<std::uint8_t>(y);
    for (int x = 0; x < truth.cols; ++x) {
      if (r != nullptr && r[x] == 0) continue;
      const bool is_true = t[x] != 0;
      const bool is_predicted = p != nullptr && p[x] != 0;
      counts.true_positive += static_cast<std::uint64_t>(is_true && is_predicted);
      counts.false_positive += static_cast<std::uint64_t>(!is_true && is_predicted);
      counts.false_negative += static_cast<std::uint64_t>(is_true && !is_predicted);
    }
  }
  return counts;
}

void MaskAccumulator::add(const MaskCounts& frame) {
  ++frames_;
  total_ += frame;
  if (frame.truth_pixels() > 0) {
    ++dynamic_frames_;
    iou_sum_ += frame.iou();
  } else {
    ++static_frames_;
    static_false_positive_ += frame.false_positive;
    if (frame.false_positive > 0) ++static_frames_with_false_positives_;
  }
}

MaskSummary MaskAccumulator::summary() const {
  MaskSummary s;
  s.frames = frames_;
  s.dynamic_frames = dynamic_frames_;
  s.mean_iou = dynamic_frames_ > 0 ? iou_sum_ / static_cast<double>(dynamic_frames_) : kNaN;
  s.precision = ratio(total_.true_positive, total_.predicted_pixels());
  s.recall = ratio(total_.true_positive, total_.truth_pixels());
  s.static_frames = static_frames_;
  s.static_false_positive = static_false_positive_;
  s.static_frames_with_false_positives = static_frames_with_false_positives_;
  s.total = total_;
  return s;
}

nlohmann::json to_json(const MaskSummary& s) {
  return {{"frames", s.frames},
          {"dynamic_frames", s.dynamic_frames},
          {"mean_iou", number(s.mean_iou)},
          {"precision", number(s.precision)},
          {"recall", number(s.recall)},
          {"static_frames", s.static_frames},
          {"static_false_positive_px", s.static_false_positive},
          {"static_frames_with_false_positives", s.static_frames_with_false_positives},
          {"tp_px", s.total.true_positive},
          {"fp_px", s.total.false_positive},
          {"fn_px", s.total.false_negative}};
}

}  // namespace ddl::eval
