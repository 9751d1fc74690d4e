#pragma once
// Trimming a CNN mask to the depth of the object it covers. The segmentation network sees the
// image at a quarter of its pixels (320x240), so its upsampled mask spills a few pixels past a
// person's outline onto whatever lies behind; a reused mask (dynamic.segmentation_interval) is
// also grown to cover the motion since its frame. Behind a person there is usually background
// well farther away, so per connected region the pixels deeper than the region's median depth
// plus a band are dropped. The median comes from the region's core (the mask eroded), where the
// spill does not reach. Nearer pixels are kept (an arm reaching towards the camera, a desk edge
// in front of a sitting person stays marked: it is safer to lose a few static pixels than to
// cut a person). docs/dynamics.md, "CNN mask trimmed by depth", has the measurements.
// Pure function: thread-safe.

#include <opencv2/core.hpp>

namespace ddl::dynamics {

struct DepthTrimConfig {
  bool enabled = true;        // false = the CNN mask as the network gives it
  double band_m = 0.4;        // keep pixels up to this much deeper than the region's median
  int core_erode_px = 4;      // the median is taken over the region eroded by this much
  int min_core_samples = 20;  // fewer valid core depths: the whole region's depths are used

  /// Throws ddl::ConfigError naming "dynamic.depth_trim.<field>".
  void validate() const;
};

/// `mask` (CV_8UC1, non-zero = dynamic) without the pixels whose depth (`depth_m`, CV_32FC1
/// metres, 0 = none) exceeds their connected region's median depth by more than band_m. Pixels
/// without depth are kept. Returns a new buffer; `mask` is not changed.
cv::Mat trim_mask_by_depth(const cv::Mat& mask, const cv::Mat& depth_m,
                           const DepthTrimConfig& config);

}  // namespace ddl::dynamics
