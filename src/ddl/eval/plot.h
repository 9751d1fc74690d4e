#pragma once
// Evaluation plots, each written twice: a PNG drawn with OpenCV (axes, ticks, grid, labels, legend)
// and an SVG written as text from the same figure description, so both show the same thing.
//  1. trajectory_top_view: ground truth (black), aligned estimate (blue) and the ATE difference
//     segments between associated poses (red), like TUM's evaluate_ate.py --plot and Fig. 5 of the
//     DDL-SLAM paper. Equal scale on both axes.
//  2. ate_over_time: translational ATE of each associated pose over time, with its RMSE.
//  3. rpe_over_time: translational RPE of each pair over time (stamp of its first pose), with RMSE.
// Lines break where stamps jump by more than 4 median intervals (lost tracking shows as a gap).
// Time axes are seconds since the first estimated pose.

#include <Eigen/Core>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "ddl/eval/evaluate.h"

namespace ddl::eval {

struct Rgb {
  unsigned char r = 0;
  unsigned char g = 0;
  unsigned char b = 0;
};

struct PlotSeries {
  std::string label;  // legend entry; empty = not listed
  Rgb color;
  double width_px = 1.5;
  /// Each inner list is drawn as one connected line (two points = one segment).
  std::vector<std::vector<Eigen::Vector2d>> polylines;
};

struct Figure {
  std::string title;
  std::string x_label;
  std::string y_label;
  bool equal_aspect = false;  // same metres per pixel on both axes (top views)
  bool y_from_zero = false;   // y axis starts at 0 (error plots)
  int width_px = 1000;
  int height_px = 750;
  std::vector<PlotSeries> series;  // drawn in order, later on top
};

/// The figure as a BGR image (CV_8UC3).
cv::Mat render_png_image(const Figure& figure);
/// The figure as a standalone SVG document.
std::string render_svg(const Figure& figure);
/// Writes `stem`.png and `stem`.svg (creating folders); returns both paths. Throws
/// ddl::InputError naming the file that cannot be written.
std::vector<std::string> write_figure(const Figure& figure, const std::string& stem);

/// Plane of the top view: the two world axes shown.
enum class Plane { kXY, kXZ, kYZ };
/// "xy", "xz" or "yz"; throws ddl::ConfigError naming key "plane" otherwise.
Plane parse_plane(const std::string& text);
std::string to_string(Plane plane);

Figure trajectory_top_view(const EvalResult& result, Plane plane = Plane::kXY);
Figure ate_over_time(const EvalResult& result);
Figure rpe_over_time(const EvalResult& result);

/// Writes the three figures into `dir` as trajectory_<plane>, ate_over_time and rpe_over_time
/// (.png and .svg). Returns the paths written.
std::vector<std::string> write_eval_plots(const EvalResult& result, const std::string& dir,
                                          Plane plane = Plane::kXY);

}  // namespace ddl::eval
