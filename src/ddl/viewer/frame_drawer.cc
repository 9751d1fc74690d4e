#include "ddl/viewer/frame_drawer.h"

#include <fmt/format.h>

#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <string>

namespace ddl::viewer {
namespace {

void check_mask(const cv::Mat& mask, const cv::Size& size, const char* name) {
  if (mask.empty()) return;
  if (mask.type() != CV_8UC1 || mask.size() != size) {
    throw std::invalid_argument(
        fmt::format("draw_frame: the {} mask must be CV_8UC1 of the image's size ({}x{})", name,
                    size.width, size.height));
  }
}

// Blends `colour` into `image` where `mask` is non-zero and `taken` is still zero; marks those
// pixels taken.
void tint(cv::Mat& image, const cv::Mat& mask, const cv::Scalar& colour, double alpha,
          cv::Mat& taken) {
  if (mask.empty()) return;
  const cv::Vec3d c(colour[0], colour[1], colour[2]);
  for (int y = 0; y < image.rows; ++y) {
    const std::uint8_t* m = mask.ptr<std::uint8_t>(y);
    std::uint8_t* t = taken.ptr<std::uint8_t>(y);
    cv::Vec3b* p = image.ptr<cv::Vec3b>(y);
    for (int x = 0; x < image.cols; ++x) {
      if (m[x] == 0 || t[x] != 0) continue;
      t[x] = 1;
      for (int k = 0; k < 3; ++k) {
        p[x][k] = cv::saturate_cast<std::uint8_t>((1.0 - alpha) * p[x][k] + alpha * c[k]);
      }
    }
  }
}

}  // namespace

cv::Mat draw_frame(const ViewFrame& frame, double mask_alpha) {
  if (frame.rgb.empty() || frame.rgb.type() != CV_8UC3) {
    throw std::invalid_argument("draw_frame: the image must be a non-empty CV_8UC3");
  }
  const cv::Size size = frame.rgb.size();
  check_mask(frame.cnn, size, "CNN");
  check_mask(frame.geometry, size, "geometry");
  check_mask(frame.memory, size, "memory");

  cv::Mat panel(size.height + kStatusBarPx, size.width, CV_8UC3, cv::Scalar::all(0));
  cv::Mat image = panel(cv::Rect(0, 0, size.width, size.height));
  frame.rgb.copyTo(image);
  cv::Mat taken = cv::Mat::zeros(size, CV_8UC1);
  tint(image, frame.cnn, kCnnColour, mask_alpha, taken);
  tint(image, frame.geometry, kGeometryColour, mask_alpha, taken);
  tint(image, frame.memory, kMemoryColour, mask_alpha, taken);

  int matched = 0;
  for (const ViewKeypoint& k : frame.keypoints) {
    if (k.matched) {
      ++matched;
      const cv::Point2f d(2.5f, 2.5f);
      cv::rectangle(image, k.pixel - d, k.pixel + d, kMatchedColour, 1);
      cv::circle(image, k.pixel, 1, kMatchedColour, cv::FILLED);
    } else {
      cv::circle(image, k.pixel, 2, kUnmatchedColour, cv::FILLED);
    }
  }

  std::string status = fmt::format("frame {}  {}  matched {}/{}  keyframes {}", frame.index,
                                   frame.state.empty() ? "?" : frame.state, matched,
                                   frame.keypoints.size(), frame.keyframes);
  if (frame.map_reset) status += "  MAP RESET";
  cv::putText(panel, status, cv::Point(6, size.height + kStatusBarPx - 9), cv::FONT_HERSHEY_SIMPLEX,
              0.5, cv::Scalar::all(255), 1, cv::LINE_AA);
  return panel;
}

}  // namespace ddl::viewer
