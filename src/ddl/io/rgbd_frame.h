#pragma once
// One RGB-D observation as the pipeline consumes it: undistorted colour and metric depth,
// registered to the colour camera.

#include <cstddef>
#include <opencv2/core.hpp>
#include <optional>
#include <string>

#include "ddl/core/types.h"

namespace ddl::io {

struct RgbdFrame {
  std::size_t index = 0;   // position in the sequence, 0-based
  double timestamp_s = 0;  // RGB timestamp, seconds (TUM: Unix time)
  /// The depth image's own stamp (TUM: depth.txt), seconds; nullopt: the RGB stamp.
  std::optional<double> depth_timestamp_s;
  cv::Mat rgb;           // CV_8UC3, BGR, undistorted
  cv::Mat depth_m;       // CV_32FC1, metres along the optical axis, 0 = no measurement
  std::string rgb_path;  // source files, for messages and outputs
  std::string depth_path;
  /// Up (unit vector) in the camera frame from the sequence's accelerometer at this frame's
  /// stamp (io::AccelerometerLog); nullopt without one.
  std::optional<Vec3d> up_c;
};

}  // namespace ddl::io
