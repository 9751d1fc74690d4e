#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>

#include "ddl/core/error.h"
#include "ddl/eval/plot.h"
#include "ddl/eval/report.h"
#include "eval_test_support.h"

namespace ddl::eval {
namespace {

// A circle walked at 32 Hz for 4 s; the estimate has a small wobble so errors are non-zero.
EvalResult small_result() {
  io::Trajectory gt;
  io::Trajectory est;
  for (int k = 0; k < 128; ++k) {
    const double t = k / 32.0;
    const Vec3d p(std::cos(t), std::sin(t), 0.1 * t);
    gt.emplace_back(100.0 + t, SE3(so3_exp(Vec3d(0, 0, t)), p));
    est.emplace_back(100.0 + t,
                     SE3(so3_exp(Vec3d(0, 0, t)), p + 0.02 * Vec3d(std::sin(5 * t), 0, 0)));
  }
  return evaluate(gt, est, EvalOptions{}, "gt.txt", "est.txt");
}

int count_occurrences(const std::string& text, const std::string& part) {
  int n = 0;
  for (std::size_t pos = text.find(part); pos != std::string::npos;
       pos = text.find(part, pos + 1)) {
    ++n;
  }
  return n;
}

TEST(PlotTest, PngShowsEachSeriesColourAndSvgHasEveryLine) {
  Figure f;
  f.title = "test";
  f.x_label = "x [m]";
  f.y_label = "y [m]";
  PlotSeries a;
  a.label = "red";
  a.color = {255, 0, 0};
  a.width_px = 3;
  a.polylines = {{{0, 0}, {1, 1}}, {{0, 1}, {1, 0}}};
  PlotSeries b;
  b.label = "green";
  b.color = {0, 200, 0};
  b.width_px = 3;
  b.polylines = {{{0, 0.5}, {0.5, 0.5}, {1, 0.5}}};
  f.series = {a, b};

  const cv::Mat img = render_png_image(f);
  ASSERT_EQ(img.type(), CV_8UC3);
  EXPECT_EQ(img.cols, f.width_px);
  EXPECT_EQ(img.rows, f.height_px);
  int red = 0;
  int green = 0;
  for (int y = 0; y < img.rows; ++y) {
    for (int x = 0; x < img.cols; ++x) {
      const cv::Vec3b c = img.at<cv::Vec3b>(y, x);
      red += c == cv::Vec3b(0, 0, 255);
      green += c == cv::Vec3b(0, 200, 0);
    }
  }
  // Two long red diagonals and one green line across most of the plot.
  EXPECT_GT(red, 1000);
  EXPECT_GT(green, 500);

  const std::string svg = render_svg(f);
  EXPECT_EQ(svg.rfind("<svg", 0), 0u);
  EXPECT_NE(svg.find("</svg>"), std::string::npos);
  EXPECT_EQ(count_occurrences(svg, "<polyline"), 3);
  EXPECT_NE(svg.find("rgb(255,0,0)"), std::string::npos);
  EXPECT_NE(svg.find(">y [m]</text>"), std::string::npos);
}

// A diverged estimate far out (1e100 m) or a range a double cannot hold still gives a picture:
// few ticks, labels in exponent notation, no endless tick loop.
TEST(PlotTest, HugeAndInfiniteRangesStillRender) {
  for (const double far : {1e100, 1e308}) {
    Figure f;
    f.title = "far";
    f.equal_aspect = true;
    PlotSeries a;
    a.label = "est";
    a.color = {0, 0, 255};
    a.polylines = {{{-far, 0}, {far, 1}}};
    f.series = {a};
    const cv::Mat img = render_png_image(f);
    EXPECT_EQ(img.cols, f.width_px) << far;
    const std::string svg = render_svg(f);
    EXPECT_LT(svg.size(), 100000u) << far;
    EXPECT_EQ(svg.find("0000000000000000"), std::string::npos) << "fixed-point labels of " << far;
  }
}

TEST(PlotTest, EvalPlotsAreWrittenAsPngAndSvg) {
  const EvalResult r = small_result();
  const Figure top = trajectory_top_view(r, Plane::kXZ);
  EXPECT_EQ(top.x_label, "x [m]");
  EXPECT_EQ(top.y_label, "z [m]");
  ASSERT_EQ(top.series.size(), 3u);
  EXPECT_EQ(top.series[0].polylines.size(), r.ate.errors_m.size());  // one segment per pair

  const test::TempDir dir("plots");
  const auto paths = write_eval_plots(r, dir.file("plots"), Plane::kXY);
  ASSERT_EQ(paths.size(), 6u);
  for (const std::string& p : paths) {
    ASSERT_TRUE(std::filesystem::exists(p)) << p;
    if (p.ends_with(".png")) {
      EXPECT_FALSE(cv::imread(p).empty()) << p;
    }
  }
  EXPECT_THROW(parse_plane("xw"), ConfigError);

  // Without an RPE (an estimate shorter than the delta) no RPE plot is written, and the earlier
  // estimate's one in the same folder is removed instead of passing for this one's.
  EvalResult short_run = r;
  short_run.rpe = RpeResult{};
  short_run.rpe_error = "RPE: too short";
  EXPECT_EQ(write_eval_plots(short_run, dir.file("plots"), Plane::kXY).size(), 4u);
  EXPECT_FALSE(std::filesystem::exists(dir.file("plots/rpe_over_time.png")));
  EXPECT_FALSE(std::filesystem::exists(dir.file("plots/rpe_over_time.svg")));
  EXPECT_TRUE(std::filesystem::exists(dir.file("plots/ate_over_time.png")));
}

TEST(ReportTest, JsonHasTheDocumentedKeysAndTheTableTheNumbers) {
  const EvalResult r = small_result();
  const nlohmann::json j = to_json(r);
  for (const char* key : {"est_poses", "compared_pose_pairs", "rmse_m", "mean_m", "median_m",
                          "std_m", "min_m", "max_m"}) {
    EXPECT_TRUE(j["ate"].contains(key)) << key;
  }
  for (const char* key :
       {"delta_s", "compared_pose_pairs", "trans_rmse_m_per_s", "trans_mean_m_per_s",
        "trans_median_m_per_s", "trans_std_m_per_s", "rot_rmse_deg_per_s", "rot_mean_deg_per_s",
        "rot_median_deg_per_s", "rot_std_deg_per_s"}) {
    EXPECT_TRUE(j["rpe"].contains(key)) << key;
  }
  EXPECT_DOUBLE_EQ(j["ate"]["rmse_m"].get<double>(), r.ate.stats_m.rmse);
  EXPECT_DOUBLE_EQ(j["rpe"]["rot_mean_deg_per_s"].get<double>(), r.rpe.rot_deg.mean);
  EXPECT_FALSE(j["tracked"]["available"].get<bool>());
  EXPECT_TRUE(j["tracked"]["ratio"].is_null());
  EXPECT_EQ(j["alignment"]["translation"].size(), 3u);
  EXPECT_EQ(j["alignment"]["scale"].get<double>(), 1.0);

  const std::string table = format_report(r);
  EXPECT_NE(table.find(fmt::format("{:.6f}", r.ate.stats_m.rmse)), std::string::npos) << table;
  EXPECT_NE(table.find(fmt::format("{:.6f}", r.rpe.trans_m.rmse)), std::string::npos) << table;
  EXPECT_NE(table.find("unavailable"), std::string::npos) << table;

  const test::TempDir dir("report");
  write_json_report(dir.file("sub/report.json"), r);
  EXPECT_EQ(nlohmann::json::parse(test::read_text(dir.file("sub/report.json"))), j);
}

}  // namespace
}  // namespace ddl::eval
