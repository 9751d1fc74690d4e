#pragma once
// Segmentation of a rolled camera's frame turned upright first. The CNN was trained on upright
// photos: people in a frame rolled by 30 degrees or more are found far less often
// (docs/dynamics.md, Upright segmentation). Where the sequence gives the direction up in the camera
// frame (an accelerometer, io::AccelerometerLog), the frame is turned about its centre so that up
// points up the image, segmented, and the labels and mask turned back.

#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "ddl/core/types.h"
#include "ddl/segmentation/segmenter.h"

namespace ddl::segmentation {

/// The angle (radians, counter-clockwise as the image is displayed) by which to turn an image so
/// that `up_c` (up in the camera frame: x right, y down, z forward) points up the image. nullopt
/// when up lies within `min_tilt_rad` of the optical axis (the camera looks straight up or
/// down, where the image has no up).
std::optional<double> upright_turn_rad(const Vec3d& up_c, double min_tilt_rad = 0.2);

/// The 2x3 affine map (CV_64F) of an image of `size` turned by `turn_rad` about its centre
/// (counter-clockwise as displayed), keeping its size.
cv::Mat turn_about_centre(cv::Size size, double turn_rad);

/// `segmenter` on `bgr` turned by `turn_rad` (upright_turn_rad); its labels and mask turned back.
/// Called from the segmenter's thread (Segmenter::segment's rule: one thread at a time).
/// The turned image keeps the frame's size. Its corners are filled by mirroring it; pixels of
/// `bgr` that it does not hold (the frame's corners; at a quarter turn of a 640x480 frame, the
/// 80 px strips at both sides) are background in the result.
SegmentationResult segment_turned(Segmenter& segmenter, const cv::Mat& bgr,
                                  const std::string& source_path, double turn_rad);

}  // namespace ddl::segmentation
