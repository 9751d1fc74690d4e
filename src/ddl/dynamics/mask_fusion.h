#pragma once
// Combining the CNN mask and the geometry mask (DDL-SLAM section III-C: "the results of the two
// are combined"), and the border band around the combined mask inside which features are not used
// either (section III-D: keypoints on the edge of a dynamic object are unreliable).
// Pure functions: thread-safe.

#include <opencv2/core.hpp>

namespace ddl::dynamics {

/// Union of the masks (either may be empty: then the other is returned; both empty: empty).
cv::Mat combine_masks(const cv::Mat& cnn_mask, const cv::Mat& geometry_mask);

/// The mask grown by `border_px` (elliptic structuring element): the features to ignore.
cv::Mat feature_exclusion_mask(const cv::Mat& dynamic_mask, int border_px);

/// Intersection over union, precision and recall of `predicted` against `truth` (non-zero = set).
struct MaskScore {
  double iou = 0.0;
  double precision = 0.0;
  double recall = 0.0;
  long true_positive = 0;
  long predicted = 0;
  long truth = 0;
};
MaskScore score_mask(const cv::Mat& predicted, const cv::Mat& truth);

}  // namespace ddl::dynamics
