#pragma once
// The frame panel of the viewer (ORB-SLAM2's FrameDrawer): the colour image with the dynamic
// masks tinted by the part that marked them and the keypoints tracking used, plus a status line.
//
// Colours (BGR): CNN mask red, geometry-check mask yellow, dynamic-memory recall magenta (a pixel
// in several masks takes the first of that order); keypoints matched to a map point green squares,
// the others blue dots. Thread-safety: pure function.

#include <opencv2/core.hpp>

#include "ddl/viewer/view_frame.h"

namespace ddl::viewer {

/// BGR colours of the frame panel, shared with the legend in docs/viewer.md.
inline const cv::Scalar kCnnColour(0, 0, 255);
inline const cv::Scalar kGeometryColour(0, 255, 255);
inline const cv::Scalar kMemoryColour(255, 0, 255);
inline const cv::Scalar kMatchedColour(0, 255, 0);
inline const cv::Scalar kUnmatchedColour(255, 128, 0);

/// Status bar height in pixels, below the image.
inline constexpr int kStatusBarPx = 28;

/// The panel: the image (its size) with a kStatusBarPx status bar below. `mask_alpha` in [0, 1]
/// is the tint's weight. Throws std::invalid_argument for an empty or non-CV_8UC3 image, or a
/// non-empty mask that is not CV_8UC1 of the image's size.
cv::Mat draw_frame(const ViewFrame& frame, double mask_alpha = 0.45);

}  // namespace ddl::viewer
