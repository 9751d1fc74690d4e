#pragma once
// Dropping the CNN regions that are pictures. The network labels what a region looks like, so a
// poster of birds or a photograph of a person on a wall is "bird" or "person" to it, and the
// masks would take a piece of the static room out of tracking for as long as the picture is in
// view. A real object of a dynamic class stands in front of something: somewhere on it, or on the
// surface it continues into, the depth image shows an occluding contour, where the background
// beside it lies farther away. A picture lies on its wall: the surface it is painted on continues
// past its outline without such a contour nearby.
//
// Each connected region of the mask is flooded over depth-continuous pixels (neighbours closer
// in depth than continuity_m + continuity_quadratic * z^2) up to reach_px steps beyond it; the
// region is kept when the flooded area holds at least min_near_pixels near-side contour pixels
// (a valid pixel with a valid pixel within contour_window_px that is farther by more than
// contour_m + contour_quadratic * z^2), and dropped otherwise. The flood crosses no depth
// dropout, so a close person whose mask covers only part of the body still reaches the body's
// own outline. A region without depth is kept (nothing to judge). docs/dynamics.md, "Pictures",
// has the measurements.
// Pure function: thread-safe.

#include <opencv2/core.hpp>

namespace ddl::dynamics {

struct PictureVetoConfig {
  bool enabled = true;  // false = every CNN region is kept, a picture of a person on a wall too
  int reach_px = 40;    // flood steps (8-neighbour) beyond the region's pixels
  double continuity_m = 0.03;          // neighbours closer in depth than this, ...
  double continuity_quadratic = 0.02;  // ... plus this times depth^2 (1/m), are one surface
  int contour_window_px = 3;  // near-side contour: a valid pixel this close (bridges dropouts) ...
  double contour_m = 0.05;    // ... lies farther by more than this ...
  double contour_quadratic = 0.03;  // ... plus this times depth^2 (1/m)
  int min_near_pixels = 10;  // contour pixels the flooded area needs; fewer: a picture, dropped

  /// Throws ddl::ConfigError naming "dynamic.picture_veto.<field>".
  void validate() const;
};

struct PictureVetoStats {
  int regions = 0;      // connected regions of the input mask
  int dropped = 0;      // regions judged to be pictures
  long dropped_px = 0;  // their pixels
};

/// `mask` (CV_8UC1, non-zero = dynamic class) without the regions that stand in front of
/// nothing in `depth_m` (CV_32FC1 metres, 0 = none). Returns a new buffer; `mask` is not changed.
cv::Mat drop_pictures(const cv::Mat& mask, const cv::Mat& depth_m, const PictureVetoConfig& config,
                      PictureVetoStats* stats = nullptr);

}  // namespace ddl::dynamics
