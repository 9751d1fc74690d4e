#pragma once
// A side-by-side picture of one generated frame for documentation and quick checks:
// RGB | depth (colourised, black = no measurement) | dynamic mask over a dimmed RGB | background.

#include <opencv2/core.hpp>

#include "ddl/synthetic/sequence.h"

namespace ddl::synthetic {

/// Four panels of `panel_size` each, left to right, with a label in each panel. CV_8UC3.
cv::Mat make_preview(const FrameData& frame, double depth_factor,
                     cv::Size panel_size = cv::Size(320, 240));

/// Colourised depth: near red to far blue over [0.5, 5] m, black where depth is 0.
cv::Mat colorize_depth(const cv::Mat& depth_raw, double depth_factor);

}  // namespace ddl::synthetic
