#include "ddl/segmentation/upright.h"

#include <cmath>
#include <opencv2/imgproc.hpp>

#include "ddl/core/timing.h"

namespace ddl::segmentation {

std::optional<double> upright_turn_rad(const Vec3d& up_c, double min_tilt_rad) {
  const double in_plane = std::hypot(up_c.x(), up_c.y());
  if (!(in_plane > 0.0) || std::atan2(in_plane, std::abs(up_c.z())) < min_tilt_rad) {
    return std::nullopt;
  }
  // Image up is -y. A counter-clockwise turn (as displayed, y down) by a takes the direction
  // (x, y) = (sin b, -cos b) to (sin(b - a), -cos(b - a)): a = b turns up to -y.
  return std::atan2(up_c.x(), -up_c.y());
}

cv::Mat turn_about_centre(cv::Size size, double turn_rad) {
  const cv::Point2f centre(0.5f * static_cast<float>(size.width - 1),
                           0.5f * static_cast<float>(size.height - 1));
  return cv::getRotationMatrix2D(centre, turn_rad * 180.0 / M_PI, 1.0);
}

SegmentationResult segment_turned(Segmenter& segmenter, const cv::Mat& bgr,
                                  const std::string& source_path, double turn_rad) {
  const Stopwatch watch;
  const cv::Mat forward = turn_about_centre(bgr.size(), turn_rad);
  // The corners the turn brings in are mirrored from the image: black corners cost ESPNetv2 more
  // of the people (docs/dynamics.md, Upright segmentation).
  cv::Mat turned;
  cv::warpAffine(bgr, turned, forward, bgr.size(), cv::INTER_LINEAR, cv::BORDER_REFLECT_101);
  SegmentationResult result = segmenter.segment(turned, source_path);
  cv::Mat back;
  cv::invertAffineTransform(forward, back);
  const auto turn_back = [&](cv::Mat& image) {
    if (image.empty()) return;
    cv::Mat out;
    cv::warpAffine(image, out, back, bgr.size(), cv::INTER_NEAREST, cv::BORDER_CONSTANT);
    image = out;
  };
  turn_back(result.labels);
  turn_back(result.dynamic_mask);
  result.inference_ms = watch.elapsed_ms();
  return result;
}

}  // namespace ddl::segmentation
