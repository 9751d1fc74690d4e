#pragma once
// Multi-view geometry check for dynamic content (DDL-SLAM section III-C, Algorithm 1, after
// DynaSLAM): keypoints with depth from reference keyframes are projected into the current frame
// with its low-cost pose; where the projected depth z_proj exceeds the depth measured around that
// pixel by more than tau, something now stands in front of what the keyframe saw there. Points
// whose parallax angle between the two viewing rays exceeds max_parallax_deg are skipped (at wide
// angles self-occlusion looks like motion). A candidate becomes a seed only when the reference
// confirms it (back-check): the current measurement, projected into the reference, lies in space
// the reference saw as empty (its depth image there is farther by more than tau). The seeds are
// grown into regions over the depth image (flood fill over depth-continuous pixels within a band
// around the seed's depth) that stops at pixels every reference saw as the same static surface.
// The result is combined with the CNN mask by the caller (mask_fusion.h). docs/dynamics.md,
// "Multi-view geometry check", explains the threshold model and the measurements behind it.
//
// Threshold: tau(z) = depth_threshold_m + depth_threshold_quadratic * z^2, like the Kinect depth
// noise and disparity quantisation, which both grow with z^2 (Nguyen et al. 3DIMPVT 2012;
// Khoshelham and Elberink, Sensors 2012). Both depth comparisons look at a (2 r + 1)^2 window
// (r = window_radius_px) and need all its valid pixels to agree, so a projection a few pixels off
// at a depth edge (pose error, rounding, edge dropouts) is not taken for motion. On fast motion
// the window grows with the point's image motion since the previous frame (motion_window_gain),
// which absorbs the RGB-depth time offset and rolling shutter of real sensors; windows wider than
// 9x9 are sampled with a step of ceil(r / 4), up to 9x9 samples (whose reach can fall a few
// pixels short of r: measured and kept, geometry_check.cc).
// Pure functions of their inputs: thread-safe.

#include <functional>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"

namespace ddl::dynamics {

/// How region growth is stopped (GeometryCheckConfig::growth_veto).
enum class GrowthVeto {
  kAll,           // YAML "all"
  kAnyUnrefuted,  // YAML "any_unrefuted"
};

struct GeometryCheckConfig {
  int max_reference_keyframes = 5;          // reference keyframes with most overlap (paper: 5)
  double max_parallax_deg = 30.0;           // skip points seen under a wider angle (paper: 30 deg)
  double depth_threshold_m = 0.03;          // tau at z = 0: constant part of the depth tests
  double depth_threshold_quadratic = 0.01;  // tau grows by this times z^2 (metres per metre^2)
  double min_depth_m = 0.3;                 // ignore measurements closer than this
  double max_depth_m = 6.0;                 // and farther than this
  int max_points_per_keyframe = 1000;       // subsample keyframe points beyond this (evenly)
  int window_radius_px = 4;                 // seed tests: a (2r+1)^2 window must agree (edges)
  /// Seed windows grow by this times the point's image motion since the previous frame: the
  /// depth image is taken up to half a frame apart from the colour image that gave the pose
  /// (TUM: up to 20 ms) and rows are exposed one after another (rolling shutter), so on fast
  /// motion depth and pose disagree by a share of that motion at every depth edge.
  double motion_window_gain = 0.5;
  int max_window_radius_px = 24;      // cap of the motion-grown seed window
  int min_seed_support = 2;           // seeds needed inside a grown region to keep it (real depth:
                                      // lone seeds at noisy edges grew false regions)
  double region_depth_band_m = 0.25;  // flood fill: |depth - seed depth| below this joins
  int region_max_radius_px = 200;     // flood fill stays inside this radius around its seed
  /// Which references stop a region from growing into a pixel: all (every reference saw the
  /// same surface there; one that could not see it lets the region in) or any_unrefuted (one
  /// reference saw the same surface outside its own dynamic mask, and none saw through it).
  GrowthVeto growth_veto = GrowthVeto::kAll;
  int dilation_px = 2;  // final dilation of the geometry mask
  /// Safety net: more seeds than this fraction of the points tested is taken for a bad pose, and
  /// the frame gets no geometry mask. 1 = off (default: with motion-grown windows real fast
  /// motion stays below 5%, while people near the camera hide up to 2/3 of the points).
  double max_seed_fraction = 1.0;
  /// Safety net for a bad pose: when the median over the tested points of |measured - projected
  /// depth| / tau exceeds this, the frame gets no geometry mask. With the right pose it is the
  /// depth noise over tau (syn_walking_rpy: at most 0.28, people included); on real fast motion
  /// (fr1_rpy) the low-cost pose is off at times and it reaches 2. A median cannot tell a bad
  /// pose from an object that hides more than half of the reference points (a walker close to
  /// the camera: 10 frames of syn_walking_xyz; docs/dynamics.md, "Pose-quality gate").
  double max_median_residual_ratio = 0.6;

  /// tau(z), the depth difference that counts as a change at depth z.
  double threshold_at(double z) const {
    return depth_threshold_m + depth_threshold_quadratic * z * z;
  }

  /// Throws ddl::ConfigError naming "dynamic.geometry.<field>" (its place in the settings).
  void validate() const;
};

/// What a reference keyframe contributes: its pose, its keypoints with valid depth and, when
/// available, its depth image.
struct ReferenceView {
  SE3 T_w_c;                        // keyframe camera -> world
  std::vector<cv::Point2f> pixels;  // undistorted keypoint positions
  std::vector<float> depth_m;       // measured depth at each keypoint (> 0)
  /// Full depth image of the keyframe (CV_32FC1 metres). Without it the reference gives no seeds
  /// (a candidate cannot be checked back) and says nothing about where regions may grow.
  cv::Mat depth_image_m;
  /// The keyframe's own dynamic mask (CV_8UC1, non-zero = dynamic), when available: where it
  /// marked something, its view is no evidence of a static surface (growth_veto any_unrefuted).
  cv::Mat dynamic_mask;
};

struct GeometryCheckStats {
  int points_tested = 0;
  int points_skipped_parallax = 0;
  int points_dynamic = 0;                   // seeds
  int points_rejected_static_occluder = 0;  // candidates the reference did not confirm
  bool implausible = false;                 // seeds above max_seed_fraction: no mask for this frame
  double median_motion_px = 0.0;            // median image motion of the tested points
  /// Median over the tested points of |measured - projected depth| / tau(z): about the sensor
  /// noise over tau when the pose is right and most points are static, above 1 when the pose is
  /// off by more than tau (or when something new hides more than half of the points).
  double median_residual_ratio = 0.0;
};

/// Dynamic seed pixels and grown regions, CV_8UC1 255 = dynamic, the size of `depth_m`.
/// `depth_m`: current frame depth (CV_32FC1, metres, 0 = none); `T_c_w`: its pose estimate;
/// `T_c_w_previous`: the previous frame's pose, when known, which sizes the seed windows
/// (motion_window_gain).
cv::Mat geometry_dynamic_mask(const cv::Mat& depth_m, const SE3& T_c_w,
                              const std::vector<ReferenceView>& references,
                              const camera::PinholeCamera& camera,
                              const GeometryCheckConfig& config,
                              GeometryCheckStats* stats = nullptr,
                              const std::optional<SE3>& T_c_w_previous = std::nullopt);

/// Grows seed pixels into regions of similar depth: 4-neighbours join when their depth is within
/// tau(z) of the pixel they are reached from and within region_depth_band_m of the seed's, inside
/// region_max_radius_px of the seed. `may_join(p)`, when given, is asked once per such candidate
/// and vetoes it (the geometry check passes "not seen as the same static surface by a reference").
cv::Mat grow_regions(const cv::Mat& depth_m, const std::vector<cv::Point>& seeds,
                     const GeometryCheckConfig& config,
                     const std::function<bool(cv::Point)>& may_join = {});

}  // namespace ddl::dynamics
