#include "ddl/eval/plot.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>
#include <opencv2/imgproc.hpp>

#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"
#include "ddl/eval/stats.h"
#include "ddl/io/image_output.h"

namespace ddl::eval {
namespace {

// Text sizes: Hershey scale for the PNG, font size in px for the SVG (similar visual size).
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;
constexpr double kTickScale = 0.5;
constexpr double kLabelScale = 0.6;
constexpr double kTitleScale = 0.65;
constexpr double kTickSvgPx = 13.0;
constexpr double kLabelSvgPx = 15.0;
constexpr double kTitleSvgPx = 16.0;
const cv::Scalar kTextBgr(40, 40, 40);
const cv::Scalar kGridBgr(225, 225, 225);
const cv::Scalar kFrameBgr(90, 90, 90);

cv::Size text_size(const std::string& text, double scale, int* baseline = nullptr) {
  int base = 0;
  const cv::Size s = cv::getTextSize(text, kFont, scale, 1, &base);
  if (baseline != nullptr) *baseline = base;
  return s;
}

struct Axis {
  double lo = 0.0;
  double hi = 1.0;
  std::vector<double> ticks;
  int decimals = 0;
};

// Tick step 1, 2 or 5 times a power of ten giving about `target` intervals.
double nice_step(double range, double target) {
  const double raw = range / target;
  const double mag = std::pow(10.0, std::floor(std::log10(raw)));
  const double norm = raw / mag;
  const double f = norm < 1.5 ? 1.0 : norm < 3.0 ? 2.0 : norm < 7.0 ? 5.0 : 10.0;
  return f * mag;
}

// Ticks at multiples of a nice step. Values beyond what fixed-point labels and a double's integer
// steps can show (a diverged estimate far out) get labels in exponent notation (decimals -1), or
// only the two ends of the axis; the count stays bounded whatever the range.
void make_ticks(Axis& axis, double target) {
  constexpr int kMaxTicks = 100;
  axis.ticks.clear();
  const double range = axis.hi - axis.lo;
  const double magnitude = std::max(std::abs(axis.lo), std::abs(axis.hi));
  const double step = nice_step(range, target);
  const bool drawable = std::isfinite(range) && range > 0.0 && std::isfinite(step) && step > 0.0;
  if (!drawable || magnitude / step > 1e12) {
    axis.decimals = -1;
    if (std::isfinite(axis.lo)) axis.ticks.push_back(axis.lo);
    if (std::isfinite(axis.hi) && axis.hi != axis.lo) axis.ticks.push_back(axis.hi);
    return;
  }
  axis.decimals =
      magnitude >= 1e7 ? -1 : std::max(0, static_cast<int>(-std::floor(std::log10(step) + 1e-9)));
  const double first = std::ceil(axis.lo / step - 1e-9);
  for (int k = 0; k < kMaxTicks; ++k) {
    double v = (first + k) * step;
    if (v > axis.hi + 1e-9 * step) break;
    if (std::abs(v) < 1e-9 * step) v = 0.0;  // no "-0.00"
    axis.ticks.push_back(v);
  }
}

std::string tick_label(double v, int decimals) {
  return decimals < 0 ? fmt::format("{:.3g}", v) : fmt::format("{:.{}f}", v, decimals);
}

struct Layout {
  int width = 0;
  int height = 0;
  int left = 0;  // plot rectangle in pixels
  int right = 0;
  int top = 0;
  int bottom = 0;
  Axis x;
  Axis y;
  double px(double v) const {
    return left + (v - x.lo) / (x.hi - x.lo) * static_cast<double>(right - left);
  }
  double py(double v) const {
    return bottom - (v - y.lo) / (y.hi - y.lo) * static_cast<double>(bottom - top);
  }
};

void pad_range(double& lo, double& hi, double fraction) {
  if (!(hi > lo)) {
    const double half = std::max(0.5 * std::abs(lo), 0.5);
    lo -= half;
    hi += half;
    return;
  }
  const double pad = (hi - lo) * fraction;
  lo -= pad;
  hi += pad;
}

Layout make_layout(const Figure& f) {
  Layout l;
  l.width = f.width_px;
  l.height = f.height_px;
  double xlo = std::numeric_limits<double>::infinity();
  double xhi = -xlo;
  double ylo = xlo;
  double yhi = -xlo;
  for (const PlotSeries& s : f.series) {
    for (const auto& line : s.polylines) {
      for (const Eigen::Vector2d& p : line) {
        if (!p.allFinite()) continue;
        xlo = std::min(xlo, p.x());
        xhi = std::max(xhi, p.x());
        ylo = std::min(ylo, p.y());
        yhi = std::max(yhi, p.y());
      }
    }
  }
  if (!std::isfinite(xlo)) xlo = 0.0, xhi = 1.0, ylo = 0.0, yhi = 1.0;
  pad_range(xlo, xhi, 0.03);
  if (f.y_from_zero && ylo >= 0.0) {
    ylo = 0.0;
    yhi = yhi > 0.0 ? yhi * 1.08 : 1.0;
  } else {
    pad_range(ylo, yhi, 0.05);
  }

  // Margins: title on top, x ticks + label below, y ticks + rotated label on the left.
  const int tick_h = text_size("0", kTickScale).height;
  const int label_h = text_size("Xy", kLabelScale).height;
  l.top = 20 + text_size("Xy", kTitleScale).height + 16;
  l.bottom = l.height - (tick_h + label_h + 40);
  l.right = l.width - 30;

  l.y.lo = ylo;
  l.y.hi = yhi;
  l.x.lo = xlo;
  l.x.hi = xhi;
  // Left margin depends on the y tick labels, which depend on the range (equal aspect changes it),
  // so settle the layout in two passes.
  for (int pass = 0; pass < 2; ++pass) {
    make_ticks(l.y, 8.0);
    int widest = 0;
    for (double v : l.y.ticks) {
      widest = std::max(widest, text_size(tick_label(v, l.y.decimals), kTickScale).width);
    }
    l.left = 14 + label_h + 14 + widest + 10;
    if (f.equal_aspect) {
      const double w = l.right - l.left;
      const double h = l.bottom - l.top;
      const double s = std::min(w / (xhi - xlo), h / (yhi - ylo));  // pixels per unit
      const double cx = 0.5 * (xlo + xhi);
      const double cy = 0.5 * (ylo + yhi);
      l.x.lo = cx - 0.5 * w / s;
      l.x.hi = cx + 0.5 * w / s;
      l.y.lo = cy - 0.5 * h / s;
      l.y.hi = cy + 0.5 * h / s;
    }
  }
  make_ticks(l.y, 8.0);
  make_ticks(l.x, std::max(4.0, (l.right - l.left) / 100.0));
  return l;
}

std::vector<const PlotSeries*> legend_entries(const Figure& f) {
  std::vector<const PlotSeries*> out;
  for (const PlotSeries& s : f.series) {
    if (!s.label.empty()) out.push_back(&s);
  }
  return out;
}

constexpr int kLegendRow = 22;
constexpr int kLegendSample = 28;

// Legend box in the top-right corner of the plot: x, y, width, height.
cv::Rect legend_box(const Figure& f, const Layout& l) {
  const auto entries = legend_entries(f);
  int widest = 0;
  for (const PlotSeries* s : entries)
    widest = std::max(widest, text_size(s->label, kTickScale).width);
  const int w = 10 + kLegendSample + 8 + widest + 10;
  const int h = 8 + kLegendRow * static_cast<int>(entries.size());
  return {l.right - w - 8, l.top + 8, w, h};
}

cv::Scalar bgr(const Rgb& c) {
  return {static_cast<double>(c.b), static_cast<double>(c.g), static_cast<double>(c.r)};
}

void put_text(cv::Mat& img, const std::string& text, cv::Point org, double scale) {
  cv::putText(img, text, org, kFont, scale, kTextBgr, 1, cv::LINE_AA);
}

constexpr int kShift = 4;  // sub-pixel line positions: coordinates in 1/16 px
cv::Point sub_px(double x, double y) {
  return {static_cast<int>(std::lround(x * (1 << kShift))),
          static_cast<int>(std::lround(y * (1 << kShift)))};
}

std::string xml_escape(const std::string& s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&':
        out += "&amp;";
        break;
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

std::string svg_rgb(const Rgb& c) { return fmt::format("rgb({},{},{})", c.r, c.g, c.b); }

// Splits a time-ordered series where consecutive stamps are more than kGapIntervals median
// intervals apart, so lost tracking shows as a gap, not a chord. (evaluate_ate.py's plot_traj
// breaks at 2 intervals, which on Kinect data also breaks at every single dropped frame.)
constexpr double kGapIntervals = 4.0;
std::vector<std::vector<Eigen::Vector2d>> split_at_gaps(const std::vector<double>& stamps,
                                                        const std::vector<Eigen::Vector2d>& pts) {
  std::vector<std::vector<Eigen::Vector2d>> lines;
  if (pts.empty()) return lines;
  std::vector<double> intervals;
  for (std::size_t i = 1; i < stamps.size(); ++i) intervals.push_back(stamps[i] - stamps[i - 1]);
  const double max_gap = intervals.empty() ? 0.0 : kGapIntervals * numpy_median(intervals);
  lines.emplace_back();
  for (std::size_t i = 0; i < pts.size(); ++i) {
    if (i > 0 && stamps[i] - stamps[i - 1] > max_gap) lines.emplace_back();
    lines.back().push_back(pts[i]);
  }
  return lines;
}

std::pair<int, int> plane_axes(Plane p) {
  switch (p) {
    case Plane::kXY:
      return {0, 1};
    case Plane::kXZ:
      return {0, 2};
    case Plane::kYZ:
      return {1, 2};
  }
  return {0, 1};
}

std::string per_delta(const EvalOptions& o) {
  if (o.rpe_delta_unit == DeltaUnit::kSeconds) {
    return o.rpe_delta == 1.0 ? "m/s" : fmt::format("m per {} s", o.rpe_delta);
  }
  return o.rpe_delta == 1.0 ? "m/frame" : fmt::format("m per {} frames", o.rpe_delta);
}

PlotSeries rmse_line(double rmse, double x0, double x1, const std::string& unit) {
  PlotSeries s;
  s.label = fmt::format("RMSE {:.4f} {}", rmse, unit);
  s.color = {230, 120, 0};
  s.width_px = 1.5;
  s.polylines = {{Eigen::Vector2d(x0, rmse), Eigen::Vector2d(x1, rmse)}};
  return s;
}

constexpr Rgb kBlue{31, 90, 200};
constexpr Rgb kBlack{0, 0, 0};
constexpr Rgb kRed{220, 30, 30};

}  // namespace

cv::Mat render_png_image(const Figure& f) {
  const Layout l = make_layout(f);
  cv::Mat img(l.height, l.width, CV_8UC3, cv::Scalar(255, 255, 255));

  // Grid, ticks and tick labels.
  const int tick_h = text_size("0", kTickScale).height;
  for (double v : l.x.ticks) {
    const int x = static_cast<int>(std::lround(l.px(v)));
    cv::line(img, {x, l.top}, {x, l.bottom}, kGridBgr, 1);
    cv::line(img, {x, l.bottom}, {x, l.bottom + 5}, kFrameBgr, 1);
    const std::string t = tick_label(v, l.x.decimals);
    put_text(img, t, {x - text_size(t, kTickScale).width / 2, l.bottom + 10 + tick_h}, kTickScale);
  }
  for (double v : l.y.ticks) {
    const int y = static_cast<int>(std::lround(l.py(v)));
    cv::line(img, {l.left, y}, {l.right, y}, kGridBgr, 1);
    cv::line(img, {l.left - 5, y}, {l.left, y}, kFrameBgr, 1);
    const std::string t = tick_label(v, l.y.decimals);
    put_text(img, t, {l.left - 9 - text_size(t, kTickScale).width, y + tick_h / 2}, kTickScale);
  }

  // Data, clipped to the plot rectangle.
  cv::Mat plot = img(cv::Rect(l.left, l.top, l.right - l.left + 1, l.bottom - l.top + 1));
  for (const PlotSeries& s : f.series) {
    const int thickness = std::max(1, static_cast<int>(std::lround(s.width_px)));
    for (const auto& line : s.polylines) {
      std::vector<cv::Point> pts;
      pts.reserve(line.size());
      for (const Eigen::Vector2d& p : line) {
        pts.push_back(sub_px(l.px(p.x()) - l.left, l.py(p.y()) - l.top));
      }
      if (pts.size() == 1) pts.push_back(pts.front());
      cv::polylines(plot, pts, false, bgr(s.color), thickness, cv::LINE_AA, kShift);
    }
  }
  cv::rectangle(img, {l.left, l.top}, {l.right, l.bottom}, kFrameBgr, 1);

  // Legend.
  const auto entries = legend_entries(f);
  if (!entries.empty()) {
    const cv::Rect box = legend_box(f, l);
    cv::rectangle(img, box, cv::Scalar(255, 255, 255), cv::FILLED);
    cv::rectangle(img, box, cv::Scalar(160, 160, 160), 1);
    for (std::size_t i = 0; i < entries.size(); ++i) {
      const int cy = box.y + 4 + kLegendRow * static_cast<int>(i) + kLegendRow / 2;
      cv::line(img, {box.x + 10, cy}, {box.x + 10 + kLegendSample, cy}, bgr(entries[i]->color),
               std::max(2, static_cast<int>(std::lround(entries[i]->width_px))), cv::LINE_AA);
      put_text(img, entries[i]->label, {box.x + 10 + kLegendSample + 8, cy + tick_h / 2},
               kTickScale);
    }
  }

  // Title and axis labels.
  const cv::Size title = text_size(f.title, kTitleScale);
  put_text(img, f.title, {(l.left + l.right - title.width) / 2, 20 + title.height}, kTitleScale);
  int base = 0;
  const cv::Size xl = text_size(f.x_label, kLabelScale, &base);
  put_text(img, f.x_label, {(l.left + l.right - xl.width) / 2, l.height - 14 - base}, kLabelScale);
  const cv::Size yl = text_size(f.y_label, kLabelScale, &base);
  cv::Mat label(yl.height + base + 4, yl.width + 4, CV_8UC3, cv::Scalar(255, 255, 255));
  put_text(label, f.y_label, {2, yl.height + 2}, kLabelScale);
  cv::Mat rotated;
  cv::rotate(label, rotated, cv::ROTATE_90_COUNTERCLOCKWISE);
  const int ly = std::clamp((l.top + l.bottom - rotated.rows) / 2, 0, l.height - rotated.rows);
  if (rotated.rows <= l.height) rotated.copyTo(img(cv::Rect(12, ly, rotated.cols, rotated.rows)));
  return img;
}

std::string render_svg(const Figure& f) {
  const Layout l = make_layout(f);
  std::string s;
  s += fmt::format(
      "<svg xmlns=\"http://www.w3.org/2000/svg\" width=\"{0}\" height=\"{1}\" "
      "viewBox=\"0 0 {0} {1}\" font-family=\"DejaVu Sans, Helvetica, Arial, sans-serif\">\n",
      l.width, l.height);
  s += fmt::format("<rect width=\"{}\" height=\"{}\" fill=\"white\"/>\n", l.width, l.height);
  s += "<g stroke=\"rgb(225,225,225)\" stroke-width=\"1\">\n";
  for (double v : l.x.ticks) {
    s += fmt::format("<line x1=\"{0:.2f}\" y1=\"{1}\" x2=\"{0:.2f}\" y2=\"{2}\"/>\n", l.px(v),
                     l.top, l.bottom);
  }
  for (double v : l.y.ticks) {
    s += fmt::format("<line x1=\"{1}\" y1=\"{0:.2f}\" x2=\"{2}\" y2=\"{0:.2f}\"/>\n", l.py(v),
                     l.left, l.right);
  }
  s += "</g>\n<g stroke=\"rgb(90,90,90)\" stroke-width=\"1\">\n";
  for (double v : l.x.ticks) {
    s += fmt::format("<line x1=\"{0:.2f}\" y1=\"{1}\" x2=\"{0:.2f}\" y2=\"{2}\"/>\n", l.px(v),
                     l.bottom, l.bottom + 5);
  }
  for (double v : l.y.ticks) {
    s += fmt::format("<line x1=\"{1}\" y1=\"{0:.2f}\" x2=\"{2}\" y2=\"{0:.2f}\"/>\n", l.py(v),
                     l.left - 5, l.left);
  }
  s += "</g>\n";
  s += fmt::format("<g font-size=\"{}\" fill=\"rgb(40,40,40)\">\n", kTickSvgPx);
  for (double v : l.x.ticks) {
    s += fmt::format("<text x=\"{:.2f}\" y=\"{}\" text-anchor=\"middle\">{}</text>\n", l.px(v),
                     l.bottom + 22, tick_label(v, l.x.decimals));
  }
  for (double v : l.y.ticks) {
    s += fmt::format("<text x=\"{}\" y=\"{:.2f}\" text-anchor=\"end\">{}</text>\n", l.left - 9,
                     l.py(v) + 4.5, tick_label(v, l.y.decimals));
  }
  s += "</g>\n";

  s += fmt::format(
      "<clipPath id=\"plot\"><rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\"/>"
      "</clipPath>\n<g clip-path=\"url(#plot)\" fill=\"none\" "
      "stroke-linejoin=\"round\" stroke-linecap=\"round\">\n",
      l.left, l.top, l.right - l.left, l.bottom - l.top);
  for (const PlotSeries& ser : f.series) {
    s += fmt::format("<g stroke=\"{}\" stroke-width=\"{}\">\n", svg_rgb(ser.color), ser.width_px);
    for (const auto& line : ser.polylines) {
      s += "<polyline points=\"";
      for (const Eigen::Vector2d& p : line)
        s += fmt::format("{:.2f},{:.2f} ", l.px(p.x()), l.py(p.y()));
      if (line.size() == 1) {
        s += fmt::format("{:.2f},{:.2f}", l.px(line[0].x()), l.py(line[0].y()));
      }
      s += "\"/>\n";
    }
    s += "</g>\n";
  }
  s += "</g>\n";
  s += fmt::format(
      "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"none\" "
      "stroke=\"rgb(90,90,90)\"/>\n",
      l.left, l.top, l.right - l.left, l.bottom - l.top);

  const auto entries = legend_entries(f);
  if (!entries.empty()) {
    const cv::Rect box = legend_box(f, l);
    s += fmt::format(
        "<rect x=\"{}\" y=\"{}\" width=\"{}\" height=\"{}\" fill=\"white\" "
        "stroke=\"rgb(160,160,160)\"/>\n",
        box.x, box.y, box.width, box.height);
    for (std::size_t i = 0; i < entries.size(); ++i) {
      const int cy = box.y + 4 + kLegendRow * static_cast<int>(i) + kLegendRow / 2;
      s += fmt::format(
          "<line x1=\"{}\" y1=\"{}\" x2=\"{}\" y2=\"{}\" stroke=\"{}\" "
          "stroke-width=\"{}\"/>\n",
          box.x + 10, cy, box.x + 10 + kLegendSample, cy, svg_rgb(entries[i]->color),
          std::max(2.0, entries[i]->width_px));
      s += fmt::format(
          "<text x=\"{}\" y=\"{}\" font-size=\"{}\" fill=\"rgb(40,40,40)\">{}</text>\n",
          box.x + 10 + kLegendSample + 8, cy + 4.5, kTickSvgPx, xml_escape(entries[i]->label));
    }
  }

  s += fmt::format(
      "<text x=\"{}\" y=\"{}\" font-size=\"{}\" text-anchor=\"middle\" fill=\"rgb(40,40,40)\">{}"
      "</text>\n",
      (l.left + l.right) / 2, 20 + 14, kTitleSvgPx, xml_escape(f.title));
  s += fmt::format(
      "<text x=\"{}\" y=\"{}\" font-size=\"{}\" text-anchor=\"middle\" fill=\"rgb(40,40,40)\">{}"
      "</text>\n",
      (l.left + l.right) / 2, l.height - 16, kLabelSvgPx, xml_escape(f.x_label));
  const int cy = (l.top + l.bottom) / 2;
  s += fmt::format(
      "<text x=\"24\" y=\"{0}\" font-size=\"{1}\" text-anchor=\"middle\" "
      "transform=\"rotate(-90 24 {0})\" fill=\"rgb(40,40,40)\">{2}</text>\n",
      cy, kLabelSvgPx, xml_escape(f.y_label));
  s += "</svg>\n";
  return s;
}

std::vector<std::string> write_figure(const Figure& figure, const std::string& stem) {
  create_parent_folder(stem, "the plots");
  const std::string png = stem + ".png";
  const std::string svg = stem + ".svg";
  io::write_png(png, render_png_image(figure), "the plot");
  write_file_atomically(svg, "the plot", render_svg(figure));
  return {png, svg};
}

Plane parse_plane(const std::string& text) {
  if (text == "xy") return Plane::kXY;
  if (text == "xz") return Plane::kXZ;
  if (text == "yz") return Plane::kYZ;
  throw ConfigError::for_key("plane", fmt::format("'{}' is not one of xy, xz, yz", text));
}

std::string to_string(Plane plane) {
  switch (plane) {
    case Plane::kXY:
      return "xy";
    case Plane::kXZ:
      return "xz";
    case Plane::kYZ:
      return "yz";
  }
  return "xy";
}

Figure trajectory_top_view(const EvalResult& r, Plane plane) {
  const auto [a, b] = plane_axes(plane);
  const char* names = "xyz";
  Figure f;
  f.title = fmt::format("Trajectory, {}-{} plane: ATE RMSE {:.4f} m over {} pairs", names[a],
                        names[b], r.ate.stats_m.rmse, r.ate.stats_m.count);
  f.x_label = fmt::format("{} [m]", names[a]);
  f.y_label = fmt::format("{} [m]", names[b]);
  f.equal_aspect = true;

  PlotSeries diff;
  diff.label = "difference";
  diff.color = kRed;
  diff.width_px = 1.0;
  for (Eigen::Index k = 0; k < r.ate.gt_xyz.cols(); ++k) {
    diff.polylines.push_back(
        {Eigen::Vector2d(r.ate.gt_xyz(a, k), r.ate.gt_xyz(b, k)),
         Eigen::Vector2d(r.ate.est_xyz_aligned(a, k), r.ate.est_xyz_aligned(b, k))});
  }

  PlotSeries gt;
  gt.label = "ground truth";
  gt.color = kBlack;
  gt.width_px = 1.2;
  std::vector<double> gt_stamps;
  std::vector<Eigen::Vector2d> gt_pts;
  for (const io::StampedPose& p : r.groundtruth) {
    gt_stamps.push_back(p.timestamp_s);
    gt_pts.emplace_back(p.t_w_c[a], p.t_w_c[b]);
  }
  gt.polylines = split_at_gaps(gt_stamps, gt_pts);

  PlotSeries est;
  est.label = r.options.align_scale ? "estimated (aligned, scaled)" : "estimated (aligned)";
  est.color = kBlue;
  est.width_px = 1.2;
  std::vector<Eigen::Vector2d> est_pts;
  for (Eigen::Index k = 0; k < r.ate.est_all_xyz_aligned.cols(); ++k) {
    est_pts.emplace_back(r.ate.est_all_xyz_aligned(a, k), r.ate.est_all_xyz_aligned(b, k));
  }
  est.polylines = split_at_gaps(r.ate.est_all_stamps_s, est_pts);

  // Differences underneath so both trajectories stay visible.
  f.series = {diff, gt, est};
  return f;
}

Figure ate_over_time(const EvalResult& r) {
  Figure f;
  f.title = fmt::format("Absolute trajectory error (translation): RMSE {:.4f} m, max {:.4f} m",
                        r.ate.stats_m.rmse, r.ate.stats_m.max);
  f.x_label = "time since first estimated pose [s]";
  f.y_label = "ATE [m]";
  f.y_from_zero = true;
  const double t0 = r.ate.est_all_stamps_s.empty() ? 0.0 : r.ate.est_all_stamps_s.front();
  std::vector<double> stamps;
  std::vector<Eigen::Vector2d> pts;
  for (std::size_t k = 0; k < r.ate.errors_m.size(); ++k) {
    stamps.push_back(r.ate.stamps_est_s[k]);
    pts.emplace_back(r.ate.stamps_est_s[k] - t0, r.ate.errors_m[k]);
  }
  PlotSeries err;
  err.label = "translational error";
  err.color = kBlue;
  err.width_px = 1.2;
  err.polylines = split_at_gaps(stamps, pts);
  f.series.push_back(err);
  if (!pts.empty())
    f.series.push_back(rmse_line(r.ate.stats_m.rmse, pts.front().x(), pts.back().x(), "m"));
  return f;
}

Figure rpe_over_time(const EvalResult& r) {
  const std::string unit = per_delta(r.options);
  Figure f;
  f.title = fmt::format("Relative pose error (translation, delta {} {}): RMSE {:.4f} {}",
                        r.options.rpe_delta, to_string(r.options.rpe_delta_unit),
                        r.rpe.trans_m.rmse, unit);
  f.x_label = "time since first estimated pose [s]";
  f.y_label = fmt::format("RPE translation [{}]", unit);
  f.y_from_zero = true;
  const double t0 = r.ate.est_all_stamps_s.empty() ? 0.0 : r.ate.est_all_stamps_s.front();
  std::vector<double> stamps;
  std::vector<Eigen::Vector2d> pts;
  for (const RpePair& p : r.rpe.pairs) {
    stamps.push_back(p.stamp_est_0_s);
    pts.emplace_back(p.stamp_est_0_s - t0, p.trans_error_m);
  }
  PlotSeries err;
  err.label = "translational error";
  err.color = kBlue;
  err.width_px = 1.2;
  err.polylines = split_at_gaps(stamps, pts);
  f.series.push_back(err);
  if (!pts.empty())
    f.series.push_back(rmse_line(r.rpe.trans_m.rmse, pts.front().x(), pts.back().x(), unit));
  return f;
}

std::vector<std::string> write_eval_plots(const EvalResult& result, const std::string& dir,
                                          Plane plane) {
  const std::filesystem::path d(dir);
  std::vector<std::string> written;
  std::vector<std::pair<Figure, std::string>> figures = {
      {trajectory_top_view(result, plane), "trajectory_" + to_string(plane)},
      {ate_over_time(result), "ate_over_time"}};
  if (result.rpe_error.empty()) {
    figures.emplace_back(rpe_over_time(result), "rpe_over_time");
  } else {
    // An earlier estimate's RPE plot in the same folder would pass for this one's.
    for (const char* stale : {"rpe_over_time.png", "rpe_over_time.svg"}) {
      std::error_code ec;
      if (std::filesystem::is_regular_file(d / stale, ec)) std::filesystem::remove(d / stale, ec);
    }
  }
  for (const auto& [figure, name] : figures) {
    const auto paths = write_figure(figure, (d / name).string());
    written.insert(written.end(), paths.begin(), paths.end());
  }
  return written;
}

}  // namespace ddl::eval
