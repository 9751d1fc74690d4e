#pragma once
// Trimming a CNN mask to the depth of the object it covers. The segmentation network sees the
// image at a quarter of its pixels (320x240), so its upsampled mask spills a few pixels past a
// person's outline onto whatever lies behind; a reused mask (dynamic.segmentation_interval) is
// also grown to cover the motion since its frame. Behind a person there is usually background
// well farther away, so the pixels of the mask's rim (the mask minus its core, the mask eroded by
// rim_px) that lie deeper than the mean depth of the core pixels around them (within window_px)
// plus a band are dropped. Only the rim is judged, and against the core next to it, so a second
// person farther away in the same region (two walkers crossing) keeps its mask. Nearer pixels are
// kept (an arm reaching towards the camera, a desk edge in front of a sitting person: it is safer
// to lose a few static pixels than to cut a person). docs/dynamics.md, "CNN mask trimmed by
// depth", has the measurements.
// Pure function: thread-safe.

#include <opencv2/core.hpp>

namespace ddl::dynamics {

struct DepthTrimConfig {
  bool enabled = true;  // false = the CNN mask as the network gives it
  double band_m = 0.4;  // keep rim pixels up to this much deeper than the core around them
  int rim_px = 12;      // the rim that may be cut: CNN spill plus the growth of a reused mask
  int window_px = 16;   // the core pixels within this many pixels give a rim pixel's reference

  /// Throws ddl::ConfigError naming "dynamic.depth_trim.<field>".
  void validate() const;
};

/// `mask` (CV_8UC1, non-zero = dynamic) without the rim pixels whose depth (`depth_m`, CV_32FC1
/// metres, 0 = none) exceeds the mean depth of the core pixels around them by more than band_m.
/// Pixels without depth, and rim pixels with no core pixel around, are kept. Returns a new buffer;
/// `mask` is not changed.
cv::Mat trim_mask_by_depth(const cv::Mat& mask, const cv::Mat& depth_m,
                           const DepthTrimConfig& config);

}  // namespace ddl::dynamics
