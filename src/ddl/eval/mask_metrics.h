#pragma once
// Quality of predicted dynamic masks against ground-truth masks (docs/evaluation.md, "Mask
// metrics"): per-frame pixel counts and their per-sequence summary.
//
// Conventions:
//   - a mask pixel is dynamic when non-zero; an empty cv::Mat prediction predicts nothing (every
//     truth pixel is a false negative), so a stage that produced no mask on a frame is penalised;
//   - mean IoU is over the frames whose truth has at least one dynamic pixel ("dynamic frames"),
//     an empty prediction scoring 0 there; frames without dynamic truth are left out of it (their
//     IoU is undefined or 0 by definition) and reported through their false-positive pixel count;
//   - precision and recall aggregate pixels over all frames (sum TP / sum (TP + FP), sum TP /
//     sum (TP + FN)), NaN when the denominator is 0.
// Thread-safety: plain values; MaskAccumulator is not synchronised.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>

namespace ddl::eval {

struct MaskCounts {
  std::uint64_t true_positive = 0;   // predicted dynamic and dynamic in the truth
  std::uint64_t false_positive = 0;  // predicted dynamic, static in the truth
  std::uint64_t false_negative = 0;  // dynamic in the truth, not predicted

  std::uint64_t truth_pixels() const { return true_positive + false_negative; }
  std::uint64_t predicted_pixels() const { return true_positive + false_positive; }
  /// TP / (TP + FP + FN); NaN when both masks are empty.
  double iou() const;
  MaskCounts& operator+=(const MaskCounts& other);
};

/// Counts the pixels of `predicted` against `truth` (both CV_8UC1, non-zero = dynamic). An empty
/// `predicted` predicts nothing; one of another size is scaled to the truth's size by nearest
/// neighbour (a mask computed at a lower resolution). With a non-empty `region` (CV_8UC1, the
/// truth's size) only pixels where it is non-zero count. Throws std::invalid_argument for an empty
/// or non-CV_8UC1 truth, a non-CV_8UC1 prediction or a region of the wrong size or type.
MaskCounts count_mask_pixels(const cv::Mat& predicted, const cv::Mat& truth,
                             const cv::Mat& region = {});

struct MaskSummary {
  std::size_t frames = 0;          // frames evaluated
  std::size_t dynamic_frames = 0;  // frames with dynamic truth: the frames of mean_iou
  double mean_iou = std::numeric_limits<double>::quiet_NaN();
  double precision = std::numeric_limits<double>::quiet_NaN();  // pixels, over all frames
  double recall = std::numeric_limits<double>::quiet_NaN();     // pixels, over all frames
  std::size_t static_frames = 0;                                // frames without dynamic truth
  std::uint64_t static_false_positive = 0;                      // predicted pixels on those frames
  std::size_t static_frames_with_false_positives = 0;
  MaskCounts total;  // summed over all frames
};

/// Sums per-frame counts into a MaskSummary.
class MaskAccumulator {
 public:
  void add(const MaskCounts& frame);
  MaskSummary summary() const;

 private:
  std::size_t frames_ = 0;
  std::size_t dynamic_frames_ = 0;
  double iou_sum_ = 0.0;
  std::size_t static_frames_ = 0;
  std::uint64_t static_false_positive_ = 0;
  std::size_t static_frames_with_false_positives_ = 0;
  MaskCounts total_;
};

/// {frames, dynamic_frames, mean_iou, precision, recall, static_frames, static_false_positive_px,
///  static_frames_with_false_positives, tp_px, fp_px, fn_px}; NaN as null.
nlohmann::json to_json(const MaskSummary& summary);

}  // namespace ddl::eval
