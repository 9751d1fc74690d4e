#pragma once
// Free-space check: the dense counterpart of the multi-view geometry check (geometry_check.h).
// Algorithm 1 projects the reference keyframes' keypoints into the current frame; this check
// projects the current frame's own pixels (a grid of samples with depth) into many earlier
// keyframes and lets each keyframe vote on the sample's 3-D point:
//   - free: the keyframe saw farther than the point along its ray, over a whole window around the
//     projection (it saw through the space the point now fills: something moved there), whether
//     or not its own dynamic mask covers that pixel (what it saw behind may have been a person
//     too, the space in front was still empty);
//   - static: the keyframe saw the same surface there (within tau), outside its own dynamic mask
//     grown by reference_mask_margin_px (masked: the same, inside that mask);
//   - nothing: out of view, no depth, or the keyframe saw something nearer (the point was hidden).
// A sample is dynamic when it has at least min_free_votes free votes and at most
// max_static_per_free static votes per free vote; dynamic samples become regions of at least
// min_region_px pixels. Unlike a sparse check, the votes come from many views spread over the
// past (max_reference_keyframes), so one keyframe misregistered at a depth edge by fast motion is
// outvoted, and a person cut by the image border (where the CNN misses them) is found whenever an
// earlier keyframe saw the space they now stand in. The same votes judge the regions of the other
// sources (drop_static_regions): a CNN region whose surface the keyframes saw unmasked more often
// than masked is a false detection (a blurred desk taken for a car); a person who sits still is
// masked by most keyframes and stays.
// docs/dynamics.md, "Free-space check", has the design and the measurements.
// Pure functions of their inputs: thread-safe.

#include <opencv2/core.hpp>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"

namespace ddl::dynamics {

struct FreeSpaceConfig {
  bool enabled = true;  // false = no free-space check (the paper: CNN and Algorithm 1 only)
  /// Keyframes that vote: at most this many of the cached ones that see the frame, spread evenly
  /// over them from the oldest to the newest (views from other times saw the space people now
  /// stand in while they were elsewhere).
  int max_reference_keyframes = 24;
  double min_reference_age_s = 0.3;  // keyframes this recent do not vote (they saw the same scene)
  /// A keyframe votes only when at least this share of a coarse grid of the frame's points with
  /// depth projects into its image (it looks at the same scene).
  double min_overlap = 0.25;
  int sample_stride_px = 4;                 // one sample per stride x stride pixels
  double depth_threshold_m = 0.05;          // tau at z = 0
  double depth_threshold_quadratic = 0.02;  // tau grows by this times z^2 (metres per metre^2)
  /// Samples of the frame nearer than this are not tested. The keyframes' views keep every
  /// reading below 65 m: a far one still saw the space before it empty, a near one hid what lies
  /// behind it.
  double min_depth_m = 0.3;
  double max_depth_m = 6.0;  // samples farther than this are not tested
  /// A free vote needs every valid depth of the keyframe's (2r + 1)^2 window around the
  /// projection to lie beyond the point by tau: a projection a few pixels off at a depth edge is
  /// not taken for free space.
  int window_radius_px = 2;
  int reference_mask_margin_px = 4;   // a keyframe's dynamic mask grown by this: no static votes
  int min_free_votes = 1;             // free votes a dynamic sample needs
  double max_static_per_free = 0.25;  // static votes a dynamic sample may have per free vote
  int min_region_px = 300;            // smaller regions of dynamic samples are dropped
  /// Growth of the kept regions over the depth image (Algorithm 1's "dynamic regions grown over
  /// the depth image", here from the free votes): a region takes the 4-neighbouring samples with
  /// depth in range whose depth differs from the sample it grows from by less than this plus
  /// grow_step_quadratic times z^2 (metres; a person's surface changes little from one sample to
  /// the next, the background behind them jumps), unless a keyframe saw a static surface there
  /// (a static vote). It reaches the parts of a person that no keyframe saw behind (the composite:
  /// combined IoU 0.596 -> 0.628 over four starts, docs/RESULTS.md stop 36). 0 = no growth.
  double grow_step_m = 0.1;
  double grow_step_quadratic = 0.0;  // metres per metre^2 added to grow_step_m
  /// A region grows by at most this many times its own samples (a leak along a surface the
  /// keyframes never saw, such as the floor at the image border, stays bounded).
  double grow_max_ratio = 2.0;
  /// Whether tracking drops the features in the grown parts too (drop_features set); otherwise
  /// they join the combined mask only (dense map, inpainting, outputs).
  bool grow_drops_features = false;
  /// Whether tracking drops the features in the free-space mask (like the geometry mask's).
  bool drop_features = true;
  /// drop_static_regions: a region of another source (CNN, memory, sparse geometry) is dropped
  /// from the combined mask when more than this share of its samples with depth had no free vote
  /// and more static votes than masked ones. 1 = keep every region.
  double max_static_region_share = 0.3;
  /// drop_static_regions also clears, inside the regions it keeps, the pixels around each sample
  /// the keyframes saw clearly as static background (FreeSpaceVotes::clearly_static) whose depth
  /// is within tau of the sample's (a CNN mask's spill onto the wall beside a person).
  bool carve_static_samples = true;
  /// Whether drop_static_regions judges the sparse geometry check's regions too (the CNN's and
  /// the memory's always are, unless max_static_region_share is 1).
  bool judge_geometry = true;

  double threshold_at(double z) const {
    return depth_threshold_m + depth_threshold_quadratic * z * z;
  }

  /// Throws ddl::ConfigError naming "dynamic.free_space.<field>".
  void validate() const;
};

/// A keyframe that votes, with its images prepared once (prepare_free_space_view).
struct FreeSpaceView {
  SE3 T_w_c;  // keyframe camera -> world
  /// CV_16UC2, both read at once for each vote (one cache line: the votes are bound by memory
  /// reads): [0] the smallest valid depth of the window around the pixel in millimetres (0 = none
  /// valid); [1] the depth in millimetres rounded to even, plus 1 where the keyframe's grown
  /// dynamic mask covers the pixel (below 2 = no depth).
  cv::Mat packed_mm;
};

/// The view's window minimum and grown mask, computed once when the keyframe is kept.
FreeSpaceView prepare_free_space_view(const SE3& T_w_c, const cv::Mat& depth_m,
                                      const cv::Mat& dynamic_mask, const FreeSpaceConfig& config);

/// The votes of the views on each sample of the frame: CV_8UC1 grids of the sample lattice
/// (sample (i, j) at pixel (j * stride + stride / 2, i * stride + stride / 2)), 0 where the
/// sample has no depth in range.
struct FreeSpaceVotes {
  int stride = 0;
  cv::Mat free_votes;
  cv::Mat static_votes;
  cv::Mat masked_votes;  // the keyframe saw the same surface inside its dynamic mask
  cv::Mat has_depth;     // CV_8UC1 non-zero = the sample had depth in range
  cv::Mat depth_m;       // the frame's depth image the votes are for (shares its data)

  /// Whether the keyframes saw the sample as static background: no free vote, and more static
  /// votes than masked ones.
  bool seen_static(int i, int j) const {
    return free_votes.at<std::uint8_t>(i, j) == 0 &&
           static_votes.at<std::uint8_t>(i, j) > masked_votes.at<std::uint8_t>(i, j);
  }
  /// Stricter, for carving single pixels: no free vote, and over twice as many static votes as
  /// masked ones.
  bool clearly_static(int i, int j) const {
    return free_votes.at<std::uint8_t>(i, j) == 0 &&
           static_votes.at<std::uint8_t>(i, j) > 2 * masked_votes.at<std::uint8_t>(i, j);
  }
};

struct FreeSpaceStats {
  int views = 0;            // keyframes that voted
  int samples = 0;          // samples with depth in range
  int samples_dynamic = 0;  // before the region size test
  int regions = 0;
  int regions_dropped = 0;  // of other sources, by drop_static_regions
};

/// Indices of the views that vote for a frame at pose T_c_w with depth `depth_m`: those that see
/// at least min_overlap of a coarse grid of its points, at most max_reference_keyframes of them
/// spread evenly over that list (which the caller orders oldest first).
std::vector<std::size_t> select_free_space_views(const cv::Mat& depth_m, const SE3& T_c_w,
                                                 const std::vector<SE3>& views_T_w_c,
                                                 const camera::PinholeCamera& camera,
                                                 const FreeSpaceConfig& config);

/// Votes of `views` on the samples of the frame at pose T_c_w.
FreeSpaceVotes free_space_votes(const cv::Mat& depth_m, const SE3& T_c_w,
                                const std::vector<FreeSpaceView>& views,
                                const camera::PinholeCamera& camera, const FreeSpaceConfig& config);

/// The dynamic regions of the votes at full resolution (CV_8UC1 255 = dynamic, the size of
/// `depth_m`): each pixel takes its sample's decision, pixels with depth only when it is within
/// tau of the sample's (so region edges follow depth edges inside a sample's cell). With
/// grow_step_m set the regions are grown over the depth first; `ungrown` (optional) receives the
/// mask of the regions before growth (the result itself without growth; empty without regions).
cv::Mat free_space_mask(const cv::Mat& depth_m, const FreeSpaceVotes& votes,
                        const FreeSpaceConfig& config, FreeSpaceStats* stats = nullptr,
                        cv::Mat* ungrown = nullptr);

/// `mask` without its 8-connected regions whose samples with depth were more than
/// max_static_region_share seen as static (FreeSpaceVotes::seen_static). Empty stays empty.
cv::Mat drop_static_regions(const cv::Mat& mask, const FreeSpaceVotes& votes,
                            const FreeSpaceConfig& config, FreeSpaceStats* stats = nullptr);

}  // namespace ddl::dynamics
