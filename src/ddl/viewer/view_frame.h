#pragma once
// What the viewer shows of one tracked frame: the image, its dynamic masks, the keypoints as
// tracking left them and the pose. Plain values (cv::Mat headers share their pixels); built by the
// caller from the pipeline's per-frame outcome, so the viewer does not depend on the pipeline.

#include <cstddef>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ddl/core/se3.h"

namespace ddl::viewer {

struct ViewKeypoint {
  cv::Point2f pixel;     // undistorted level-0 pixel
  bool matched = false;  // an inlier match of a map point in the frame's pose
};

struct ViewFrame {
  std::size_t index = 0;  // position in the sequence
  cv::Mat rgb;            // CV_8UC3 BGR, undistorted
  cv::Mat cnn;            // CV_8UC1 non-zero = CNN mask (may be empty)
  cv::Mat geometry;       // CV_8UC1 non-zero = geometry-check mask (may be empty)
  cv::Mat memory;         // CV_8UC1 non-zero = recalled by the dynamic memory (may be empty)
  std::vector<ViewKeypoint> keypoints;
  std::string state;          // tracking state as text ("ok", "lost", ...)
  std::optional<SE3> T_w_c;   // camera pose when tracked
  std::size_t keyframes = 0;  // keyframes created so far
  bool map_reset = false;     // tracking cleared the map on this frame
};

}  // namespace ddl::viewer
