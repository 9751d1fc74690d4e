#pragma once
// Dropping the CNN regions that are pictures. The network labels what a region looks like, so a
// poster of birds or a photograph of a person on a wall is "bird" or "person" to it, and the
// masks would take a piece of the static room out of tracking for as long as the picture is in
// view. A real object of a dynamic class stands in front of something: somewhere on it, or on the
// surface it continues into, the depth image shows the near side of an occluding contour, where
// the background beside it lies farther away or beyond the sensor's range. A picture lies on its
// wall, which continues past the picture's outline without such a contour nearby.
//
// Each connected region (8-connected) of the mask is flooded from its pixels with depth over
// 8-neighbours whose depth differs from the pixel expanded from by less than continuity_m +
// continuity_quadratic * z^2 (z: that pixel's depth), for up to reach_px steps. A pixel counts
// as a near-side contour when a valid pixel within contour_window_px (Chebyshev) lies farther by
// more than contour_m + contour_quadratic * z^2, or when a depth hole at least 2 * hole_px + 1
// pixels across lies that close. The region is kept when its pixels and the flooded pixels hold at
// least min_near_pixels contour pixels, and dropped otherwise. The window bridges the narrow
// dropout bands along contours (up to contour_window_px - 1 pixels wide); since the flood stops
// at any dropout or depth step, a close person whose mask covers only the middle of the body
// still reaches the body's own outline through the body's surface. Kept unjudged: a region
// without depth, and every region after the floods of this mask reached max_flood_pixels.
// Known limits (docs/dynamics.md, "Pictures"): a picture on a screen is kept (the screen stands
// in front of the wall); mixed depth pixels along a step can let the flood climb onto a nearer
// object and keep a picture beside it. Both err on the side of keeping a mask. Outside
// source_area nothing is a hole: the blank margin of an undistorted frame would otherwise be one
// along the image's edges. A band the depth sensor never measures (fr1's top and right, about
// 35 px) lies inside the area and still counts as a hole, keeping a picture next to it.
// Pure function: thread-safe.

#include <opencv2/core.hpp>

namespace ddl::dynamics {

struct PictureVetoConfig {
  bool enabled = true;  // false = every CNN region is kept, a picture of a person on a wall too
  int reach_px = 80;    // flood steps (8-neighbour) beyond the region's pixels
  double continuity_m = 0.03;          // neighbours closer in depth than this, ...
  double continuity_quadratic = 0.02;  // ... plus this times depth^2 (1/m), are one surface
  int contour_window_px = 3;  // near-side contour: a valid pixel this close (bridges dropouts) ...
  double contour_m = 0.05;    // ... lies farther by more than this ...
  double contour_quadratic = 0.03;  // ... plus this times depth^2 (1/m)
  int hole_px = 4;  // a depth hole 2 * hole_px + 1 px across beside a pixel is a contour too
  int min_near_pixels = 10;  // contour pixels the flooded area needs; fewer: a picture, dropped
  /// Cost bound: once the floods of one mask reached this many pixels beyond their regions, the
  /// remaining regions are kept unjudged (a mask of many specks would otherwise flood up to
  /// (2 * reach_px + 1)^2 pixels per speck).
  int max_flood_pixels = 600000;

  /// Throws ddl::ConfigError naming "dynamic.picture_veto.<field>".
  void validate() const;
};

struct PictureVetoStats {
  int regions = 0;      // connected regions of the input mask
  int dropped = 0;      // regions judged to be pictures
  long dropped_px = 0;  // their pixels
  int unjudged = 0;     // regions kept because max_flood_pixels was spent
};

/// `mask` (CV_8UC1, non-zero = dynamic class) without the regions that stand in front of
/// nothing in `depth_m` (CV_32FC1 metres, 0 = none, the mask's size; either may be an ROI).
/// `source_area` (CV_8UC1, the mask's size, or empty = everywhere): the pixels with a stored
/// pixel behind them (io::DatasetReader::source_area); a pixel outside it (the blank margin
/// undistortion leaves) is no depth hole, as the world beyond the image's edge is none. Returns a
/// new buffer; `mask` is not changed. `stats`, when given, is overwritten.
cv::Mat drop_pictures(const cv::Mat& mask, const cv::Mat& depth_m, const PictureVetoConfig& config,
                      PictureVetoStats* stats = nullptr, const cv::Mat& source_area = cv::Mat());

}  // namespace ddl::dynamics
