#pragma once
// Background inpainting from previous keyframes (DDL-SLAM section III-E): the pixels of the
// current frame hidden by dynamic objects are filled with what the last N keyframes (default 15)
// saw there (and, optionally, what older keyframes saw where those left holes). Every static pixel
// of a keyframe (outside its own dynamic mask, with depth) is back-projected with its depth, moved
// into the current camera with the optimized poses and splatted into the current frame; a z-buffer
// keeps the nearest surface, so the result is what the camera would see if the dynamic objects were
// not there. Keyframes are visited newest first and their already repaired content is used (each
// keyframe stores its repaired images), so the background spreads over time. Pixels no keyframe saw
// remain in the `unfilled` mask; an optional image-based fill (OpenCV Telea inpainting) closes
// holes smaller than `max_hole_area_px`. Two checks keep the projected content to the hidden
// background: samples within the depth tolerance (absolute + relative, as Kinect noise and
// disparity steps grow with depth) count as one surface, so the newest keyframe's centre sample
// wins over noisy older ones instead of a mosaic of sources; and a sample nearer than what the
// current frame measures at that pixel (by more than the tolerance) is rejected: the current ray is
// free up to its depth, so such a sample is content that is gone (a moving object a source
// keyframe's mask missed). With observed_first, what the keyframes observed is splatted before what
// they repaired themselves, so a repair's mistakes do not spread to later repairs where an
// observation is available. Thread-safety: pure functions of their inputs.

#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"

namespace ddl::inpainting {

struct InpaintingConfig {
  int num_keyframes = 15;  // last keyframes projected (paper: 15)
  /// Older keyframes (before the last num_keyframes) projected afterwards, only into the pixels
  /// the last num_keyframes left empty (after their repaired pixels too), and voting in the
  /// see-through check: what the camera saw from elsewhere fills holes, while recent content
  /// keeps priority. 0 = the paper's setting. 25 fills 87% instead of 68% of
  /// syn_walking_halfsphere's dynamic pixels; the dense stage then costs 6.0% of the frame
  /// rate instead of 5.4% (docs/dense.md).
  int extra_keyframes = 25;
  int splat_radius_px = 1;            // each source pixel covers (2r+1)^2 target pixels (0 = one)
  double depth_tolerance_m = 0.02;    // z-buffer: nearer by more than this wins
  double depth_tolerance_rel = 0.03;  // tolerance grows by this fraction of the depth (noise)
  bool free_space_check = true;       // reject samples in front of the current frame's depth
  /// Also reject samples at the masked pixel's own depth (within the tolerance): what hides the
  /// background there is that surface, so such a sample is the moving object itself, seen by a
  /// keyframe whose mask missed it (or static surface the mask over-covers, which the pixel
  /// already shows). The background lies behind.
  bool behind_current_only = true;
  double max_depth_m = 6.0;            // ignore samples beyond this (source and current depth)
  bool image_fill_small_holes = true;  // Telea fill for holes left after projection
  int max_hole_area_px = 400;          // only holes (connected components) up to this size
  int source_stride_px = 1;            // sample every n-th source pixel (speed/quality trade-off)
  bool resample_colour = true;  // colour read back bilinearly from the winning keyframe at the
                                // splatted depth (sub-pixel exact) instead of the splatted sample
  /// Samples from pixels a keyframe observed are splatted first; pixels it repaired itself only
  /// fill what no observed sample reached. Otherwise a piece of a person that one repair let
  /// through is copied from repair to repair and the error accumulates over the sequence.
  bool observed_first = true;
  /// Multi-view check: a filled pixel whose point at least this many other sources saw through
  /// (they saw farther along its ray, where they observed) is a piece of a moving object one
  /// source's mask missed, and is left unfilled. 0 = off.
  int see_through_votes = 2;
  /// Skip source blocks of 16 x 16 pixels that cannot reach the mask (bounded by their depth
  /// range), instead of projecting every pixel, and in the see-through check the sources that
  /// cannot vote for a 16 x 16 tile: the result is the same, sample for sample and vote for vote;
  /// false is for checking that (tests/inpainting) and for timing it.
  bool skip_unreachable_blocks = true;

  /// Throws ddl::ConfigError naming "dense.inpainting.<field>" (its place in the settings).
  void validate() const;
};

/// Smallest and largest finite positive depth of each kBlock x kBlock block of a source's depth
/// image, over the samples a pass may use (+inf and 0 where it has none, or where it was not
/// computed): `all` over the samples outside the exclude mask, `observed` over those also outside
/// the repaired mask, `repaired` over those inside it. inpaint() skips the source blocks that
/// cannot reach the mask with it (a block without repaired samples costs its repaired pass
/// nothing); a caller that keeps its sources computes it once per source.
struct DepthBlocks {
  static constexpr int kBlock = 16;
  struct Range {
    std::vector<float> z_min;
    std::vector<float> z_max;
  };
  int blocks_x = 0;
  int blocks_y = 0;
  Range all;
  Range observed;
  Range repaired;
  /// The buffers of the masks they were computed with (nullptr: none), which inpaint() checks
  /// against the SourceView's: blocks computed without the masks would skip samples a pass uses.
  const void* exclude_data = nullptr;
  const void* repaired_data = nullptr;
};

/// DepthBlocks of the whole image, with the source's exclude and repaired masks (CV_8UC1 of the
/// depth's size, non-zero = set; either may be empty). The SourceView must hold these same masks
/// (the same buffers, unchanged since): inpaint() throws ddl::Error for other buffers.
DepthBlocks depth_blocks(const cv::Mat& depth_m, const cv::Mat& exclude_mask = cv::Mat(),
                         const cv::Mat& repaired_mask = cv::Mat());

/// A keyframe as a source of background: its pose, images and the pixels not to use.
struct SourceView {
  SE3 T_w_c;
  cv::Mat bgr;      // CV_8UC3 (repaired, when available)
  cv::Mat depth_m;  // CV_32FC1 metres (repaired, when available), 0 = none
  cv::Mat
      exclude_mask;  // CV_8UC1 non-zero = do not use (dynamic pixels left unfilled); may be empty
  /// CV_8UC1 non-zero = this keyframe's own repair filled the pixel (not observed); may be empty.
  cv::Mat repaired_mask;
  /// depth_blocks(depth_m, exclude_mask, repaired_mask), when the caller keeps it; otherwise
  /// inpaint() computes what it needs.
  std::shared_ptr<const DepthBlocks> blocks = nullptr;
};

struct InpaintingResult {
  cv::Mat bgr;           // repaired colour
  cv::Mat depth_m;       // repaired depth (0 where nothing is known)
  cv::Mat filled;        // CV_8UC1 255 = masked pixel filled from keyframes
  cv::Mat image_filled;  // CV_8UC1 255 = masked pixel filled by the image-based fill
  cv::Mat unfilled;      // CV_8UC1 255 = masked pixel still unknown
  int masked_pixels = 0;
  int filled_pixels = 0;
};

/// Repairs the pixels of `mask` (non-zero) in the current frame (pose T_c_w) from `sources`
/// (ordered newest first; at most config.num_keyframes + config.extra_keyframes are used).
InpaintingResult inpaint(const cv::Mat& bgr, const cv::Mat& depth_m, const cv::Mat& mask,
                         const SE3& T_c_w, const std::vector<SourceView>& sources,
                         const camera::PinholeCamera& camera, const InpaintingConfig& config);

}  // namespace ddl::inpainting
