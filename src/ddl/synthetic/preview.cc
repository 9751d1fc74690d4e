#include "ddl/synthetic/preview.h"

#include <opencv2/imgproc.hpp>

namespace ddl::synthetic {

cv::Mat colorize_depth(const cv::Mat& depth_raw, double depth_factor) {
  cv::Mat metres;
  depth_raw.convertTo(metres, CV_32F, 1.0 / depth_factor);
  cv::Mat scaled;
  metres.convertTo(scaled, CV_8U, 255.0 / 4.5, -0.5 * 255.0 / 4.5);
  cv::Mat color;
  cv::applyColorMap(255 - scaled, color, cv::COLORMAP_JET);
  color.setTo(cv::Scalar(0, 0, 0), depth_raw == 0);
  return color;
}

cv::Mat make_preview(const FrameData& frame, double depth_factor, cv::Size panel_size) {
  cv::Mat mask_view = frame.rgb * 0.35;
  mask_view.setTo(cv::Scalar(60, 60, 255), frame.dynamic_mask);
  const cv::Mat panels[4] = {frame.rgb, colorize_depth(frame.depth_raw, depth_factor), mask_view,
                             frame.background_rgb};
  const char* labels[4] = {"rgb", "depth", "dynamic mask", "background"};
  cv::Mat out(panel_size.height, panel_size.width * 4, CV_8UC3, cv::Scalar(0, 0, 0));
  for (int k = 0; k < 4; ++k) {
    cv::Mat roi = out(cv::Rect(k * panel_size.width, 0, panel_size.width, panel_size.height));
    cv::resize(panels[k], roi, panel_size, 0, 0, cv::INTER_AREA);
    cv::putText(roi, labels[k], {6, 18}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(0, 0, 0), 3,
                cv::LINE_AA);
    cv::putText(roi, labels[k], {6, 18}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(255, 255, 255),
                1, cv::LINE_AA);
  }
  return out;
}

}  // namespace ddl::synthetic
