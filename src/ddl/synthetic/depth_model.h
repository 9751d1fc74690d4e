#pragma once
// Kinect-like depth sensor model applied to exact rendered depth.
//
//  1. Axial noise (Nguyen, Izadi, Lovell, "Modeling Kinect Sensor Noise for Improved 3D
//     Reconstruction and Tracking", 3DIMPVT 2012, eq. 6):
//        sigma_z(z, theta) = 0.0012 + 0.0019 (z - 0.4)^2 + 0.0001 / sqrt(z) * theta^2 / (pi/2 -
//        theta)^2
//     (metres; theta = angle between the ray and the surface normal).
//  2. Disparity quantisation (Khoshelham, Elberink, "Accuracy and Resolution of Kinect Depth Data
//     for Indoor Mapping Applications", Sensors 2012): depth comes from disparity d = f b / z
//     measured in 1/8 pixel, so z is quantised to f b / (round(8 f b / z) / 8); the step grows with
//     z^2 (about 1 cm at 2 m, 7 cm at 5 m). Then the TUM raw unit (1 / depth_factor m).
//  3. Missing depth (0): outside [min_range_m, max_range_m], at grazing angles (theta >
//     max_incidence_deg), and along depth discontinuities: always on the far side of a jump within
//     one pixel, with probability edge_extra_probability also on the near side and one pixel
//     further on the far side (the IR shadow / edge dropouts of structured light).
//
// The noise of a pixel is a pure function of (seed, frame, pixel), so two renderings of the same
// frame (with and without dynamic objects) get identical depth wherever the same surface is seen.

#include <cstdint>
#include <opencv2/core.hpp>

namespace ddl::synthetic {

struct DepthNoiseConfig {
  bool enabled = true;               // false: exact depth, only rounded to 1/depth_factor
  double min_range_m = 0.5;          // nearer than this: no measurement
  double max_range_m = 4.5;          // farther than this: no measurement
  double max_incidence_deg = 78.0;   // more grazing than this: no measurement
  double sigma_base_m = 0.0012;      // Nguyen et al. 2012, constant term
  double sigma_quadratic = 0.0019;   // Nguyen et al. 2012, coefficient of (z - z0)^2 (1/m)
  double sigma_offset_m = 0.4;       // Nguyen et al. 2012, z0
  double sigma_angular = 0.0001;     // Nguyen et al. 2012, lateral-angle term coefficient (m^1.5)
  double disparity_fb_px_m = 43.5;   // focal length (580 px) x baseline (0.075 m) of the Kinect
  double disparity_subpixel = 8.0;   // disparity resolution: 1/8 pixel; 0 disables quantisation
  double edge_jump_m = 0.04;         // minimum depth jump between neighbours that is an edge
  double edge_jump_relative = 0.02;  // plus this fraction of the depth
  double edge_extra_probability = 0.35;  // chance of a wider / near-side dropout at an edge pixel

  /// Throws ddl::ConfigError naming "depth.<field>".
  void validate() const;
};

/// Turns exact depth (CV_32FC1 metres, 0 = nothing) and |cos| of the incidence angle (CV_32FC1)
/// into a raw 16-bit TUM depth image (value = metres x depth_factor, 0 = no measurement).
cv::Mat apply_depth_model(const cv::Mat& depth_m, const cv::Mat& cos_incidence,
                          const DepthNoiseConfig& config, double depth_factor, std::uint64_t seed,
                          std::uint64_t frame);

/// The real surface behind missing measurements: every 0 pixel of `depth_m` (CV_32FC1 metres)
/// takes the depth of its nearest valid pixel (L2 distance). A composite uses it for its depth
/// test: a black monitor screen the sensor cannot measure still hides what is behind it, instead
/// of letting a person show through the holes of its depth. An image without any valid pixel is
/// returned unchanged.
cv::Mat fill_missing_depth_nearest(const cv::Mat& depth_m);

/// Adds zero-mean sensor noise of standard deviation about sigma (in 8-bit levels) to a BGR image,
/// deterministic per (seed, frame, pixel). sigma <= 0 leaves the image unchanged. With `only`
/// (CV_8UC1), just the pixels where it is non-zero get noise (the same values they would get
/// without it).
void add_rgb_noise(cv::Mat& bgr, double sigma, std::uint64_t seed, std::uint64_t frame,
                   const cv::Mat& only = {});

}  // namespace ddl::synthetic
