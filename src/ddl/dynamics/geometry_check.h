#pragma once
// Multi-view geometry check for dynamic content (DDL-SLAM section III-C, Algorithm 1, after
// DynaSLAM): keypoints with depth from reference keyframes are projected into the current frame
// with its low-cost pose; where the projected depth z_proj exceeds the depth measured at that pixel
// z_meas by more than a threshold, something now stands in front of what the keyframe saw there,
// so the pixel is marked dynamic. Points whose parallax angle between the two viewing rays exceeds
// max_parallax_deg are skipped (at wide angles self-occlusion looks like motion). The dynamic seed
// pixels are then grown into regions over the depth image (flood fill within a depth band around
// each seed), and the result is combined with the CNN mask by the caller (mask_fusion.h).
//
// The threshold grows with depth like the sensor noise (Kinect depth noise grows with z^2, Nguyen
// et al. 3DIMPVT 2012): tau(z) = depth_threshold_m + depth_threshold_quadratic * z^2.
// Pure functions of their inputs: thread-safe.

#include <opencv2/core.hpp>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"

namespace ddl::dynamics {

struct GeometryCheckConfig {
  int max_reference_keyframes = 5;          // reference keyframes with most overlap (paper: 5)
  double max_parallax_deg = 30.0;           // skip points seen under a wider angle (paper: 30 deg)
  double depth_threshold_m = 0.08;          // tau at z = 0: constant part of the depth test
  double depth_threshold_quadratic = 0.02;  // tau grows by this times z^2 (metres per metre^2)
  double min_depth_m = 0.3;                 // ignore measurements closer than this
  double max_depth_m = 6.0;                 // and farther than this
  int max_points_per_keyframe = 1000;       // subsample keyframe points beyond this (evenly)
  int min_seed_support = 1;                 // seeds needed inside a grown region to keep it
  double region_depth_band_m = 0.25;        // flood fill: |depth - seed depth| below this joins
  int region_max_radius_px = 200;           // flood fill stays inside this radius around its seed
  int dilation_px = 2;                      // final dilation of the geometry mask
  double occluder_agreement_m = 0.05;       // back-check tolerance (+ tau/2), see ReferenceView

  /// Throws ddl::ConfigError naming "dynamics.<field>".
  void validate() const;
};

/// What a reference keyframe contributes: its pose and its keypoints with valid depth.
struct ReferenceView {
  SE3 T_w_c;                        // keyframe camera -> world
  std::vector<cv::Point2f> pixels;  // undistorted keypoint positions
  std::vector<float> depth_m;       // measured depth at each keypoint (> 0)
  /// Optional full depth image of the keyframe (CV_32FC1 metres). When present, a candidate is
  /// checked back: the current measurement at the candidate pixel is projected into the
  /// reference; if the reference measured that same surface there, the occluder is static
  /// structure seen from a new viewpoint (occlusion, not motion) and the candidate is dropped.
  cv::Mat depth_image_m;
};

struct GeometryCheckStats {
  int points_tested = 0;
  int points_skipped_parallax = 0;
  int points_dynamic = 0;
  int points_rejected_static_occluder = 0;
};

/// Dynamic seed pixels and grown regions, CV_8UC1 255 = dynamic, the size of `depth_m`.
/// `depth_m`: current frame depth (CV_32FC1, metres, 0 = none); `T_c_w`: its pose estimate.
cv::Mat geometry_dynamic_mask(const cv::Mat& depth_m, const SE3& T_c_w,
                              const std::vector<ReferenceView>& references,
                              const camera::PinholeCamera& camera,
                              const GeometryCheckConfig& config,
                              GeometryCheckStats* stats = nullptr);

/// Grows seed pixels (non-zero in `seeds`) into regions of similar depth (see config).
cv::Mat grow_regions(const cv::Mat& depth_m, const std::vector<cv::Point>& seeds,
                     const GeometryCheckConfig& config);

}  // namespace ddl::dynamics
