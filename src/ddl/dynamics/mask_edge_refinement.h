#pragma once
// Snapping the combined dynamic mask to the colour edges of the frame. The mask's sources find
// a moving person well inside their outline but miss or overshoot its rim: the CNN sees the
// image at 320x240, the free-space regions grow over the depth image (which a real sensor
// registers to the colour image only to a few pixels) and stop where a person stands at the
// depth of what lies behind, and the memory splats sampled points. The outline itself is usually
// a colour edge. A guided filter (He, Sun and Tang, "Guided Image Filtering", ECCV 2010) with the
// colour image as guide turns the binary mask into a soft one that follows the guide's edges
// within radius_px of the mask; thresholding it gives the refined mask, which passes with a
// smaller window refine further (iterated guided filtering). The passes run at `scale` of the
// image, thresholded there, on the mask's bounding box grown by the reach of all passes: pixels
// farther from the mask come out 0 either way (the rim may move by about one filter pixel with
// the box, whose corner the resampling grid starts at). Where the guide has no edge a pass is
// a blur, so the rim leans outward by a few pixels (threshold below 0.5), corners round off, and a
// region narrower than the window on a patch of one colour fades out (CNN fragments on a wall, but
// also a person's sliver the border cuts if it matches the background). docs/dynamics.md, "Edge
// refinement", has the measurements.
// Pure function: thread-safe.

#include <opencv2/core.hpp>

namespace ddl::dynamics {

struct EdgeRefinementConfig {
  bool enabled = true;  // false = the combined mask as its sources give it
  /// Image scale the filter runs at (the mask and the guide area-resampled; the passes are
  /// thresholded at this scale). 0.375 scored as 0.5 on the composite (four starts, to the third
  /// decimal) at 3.2 against 5.9 ms per frame; 1.0 costs about four times 0.5.
  double scale = 0.375;
  /// Window radius of the first pass at full resolution (pixels). Larger radii snap farther but
  /// round off small objects and cut into people whose colours match what is behind them (offline,
  /// one pass: 24 px composite +0.048, syn_desk_person -0.03; 16 px +0.034 / +0.001).
  int radius_px = 16;
  /// Regularisation of the filter, in squared intensity (the guide scaled to 0..1): the smaller,
  /// the more closely the result follows weak edges.
  double eps = 1e-4;
  /// Soft-mask level above which a pixel is dynamic; below 0.5 the rim leans outward, where the
  /// sources miss more than they overshoot (offline, one pass: 0.5 gained 0.032 on the composite
  /// and 0.011 on syn_sitting_halfsphere, 0.4 0.039 and 0.035; 0.35 lost on the walking rooms).
  double threshold = 0.45;
  /// Passes of the filter on its own result with the smaller follow_up_radius_px: each pulls the
  /// rim closer to the edges the passes before found (offline, composite +0.034 with none, +0.049
  /// with three, +0.055 with seven; the synthetic sequences gain about as much with any number).
  int follow_up_passes = 3;
  int follow_up_radius_px = 8;  // window radius of the follow-up passes (full resolution)
  /// The mask's pixels farther than this inside it are kept whatever the filter says, so the
  /// filter moves the rim only. A small object whose outline matches what is behind it but which
  /// carries a strong inner edge (syn_desk_person's box and its printed logo) otherwise shrinks
  /// towards that edge: its combined recall 0.621 unrefined, 0.525 refined, 0.558 with 4 px
  /// (desk_person IoU 0.842 / 0.849 / 0.852; the composite 0.718 -> 0.716 with 4 px, the other
  /// sequences within 0.001). 0 = the filter decides everywhere.
  int keep_core_px = 0;
  /// Whether the free-space check's regions before their growth over the depth (its seeds'
  /// regions, DynamicMasks::free_space_regions) are kept whatever the filter says: what the
  /// depth itself shows moved is not left to the colour edges (DynamicFrontEnd passes them to
  /// refine_mask_edges as `keep`).
  /// syn_desk_person's box recall 0.646 (0.621 unrefined, 0.525 refined), desk_person IoU 0.857,
  /// sitting_halfsphere's box 0.741 (0.723), but the composite 0.711 / 0.724 / 0.697 / 0.697
  /// from start frames 0-3 (0.718 / 0.731 / 0.704 / 0.702 without): off by default.
  bool keep_free_space_regions = false;

  /// Throws ddl::ConfigError naming "dynamic.edge_refinement.<field>".
  void validate() const;
};

/// `mask` (CV_8UC1, non-zero = dynamic) snapped to the edges of `bgr` (CV_8UC3, the same size)
/// as described above; 0/255. The pixels of `keep` (CV_8UC1 within `mask`, optional) and, with
/// keep_core_px, the mask's core stay set whatever the filter says. An empty mask or one with no
/// pixel set is returned as it is. Returns a new buffer otherwise; `mask` is not changed.
cv::Mat refine_mask_edges(const cv::Mat& mask, const cv::Mat& bgr,
                          const EdgeRefinementConfig& config, const cv::Mat& keep = cv::Mat());

}  // namespace ddl::dynamics
