// Mask metrics on hand-made masks, and the benchmark tables' arithmetic.

#include "ddl/eval/mask_metrics.h"

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

#include "ddl/eval/benchmark_tables.h"

namespace ddl::eval {
namespace {

/// 4x4 mask, 255 inside the rectangle (x, y, w, h).
cv::Mat rect_mask(int x, int y, int w, int h, cv::Size size = {4, 4}) {
  cv::Mat m = cv::Mat::zeros(size, CV_8UC1);
  m(cv::Rect(x, y, w, h)).setTo(255);
  return m;
}

TEST(MaskMetrics, CountsOverlappingHalves) {
  const cv::Mat truth = rect_mask(0, 0, 2, 4);      // left half: 8 px
  const cv::Mat predicted = rect_mask(0, 0, 4, 2);  // top half: 8 px, 4 of them on the truth
  const MaskCounts c = count_mask_pixels(predicted, truth);
  EXPECT_EQ(c.true_positive, 4u);
  EXPECT_EQ(c.false_positive, 4u);
  EXPECT_EQ(c.false_negative, 4u);
  EXPECT_DOUBLE_EQ(c.iou(), 4.0 / 12.0);
  EXPECT_EQ(c.truth_pixels(), 8u);
  EXPECT_EQ(c.predicted_pixels(), 8u);
}

TEST(MaskMetrics, NonZeroIsDynamicAndEmptyPredictionPredictsNothing) {
  cv::Mat truth = rect_mask(1, 1, 2, 2);
  truth.setTo(1, truth);  // any non-zero value counts
  const MaskCounts empty = count_mask_pixels(cv::Mat(), truth);
  EXPECT_EQ(empty.true_positive, 0u);
  EXPECT_EQ(empty.false_positive, 0u);
  EXPECT_EQ(empty.false_negative, 4u);
  EXPECT_DOUBLE_EQ(empty.iou(), 0.0);
  const MaskCounts both_empty = count_mask_pixels(cv::Mat(), cv::Mat::zeros(4, 4, CV_8UC1));
  EXPECT_TRUE(std::isnan(both_empty.iou()));
}

TEST(MaskMetrics, RegionRestrictsAndLowResolutionPredictionIsScaled) {
  const cv::Mat truth = rect_mask(0, 0, 2, 4);
  const cv::Mat region = rect_mask(0, 0, 4, 2);  // top half only
  const MaskCounts c = count_mask_pixels(cv::Mat(), truth, region);
  EXPECT_EQ(c.false_negative, 4u);  // only the truth pixels in the top half
  // A 2x2 prediction with its top-left pixel set covers the 4x4 top-left quarter.
  cv::Mat small = cv::Mat::zeros(2, 2, CV_8UC1);
  small.at<std::uint8_t>(0, 0) = 255;
  const MaskCounts s = count_mask_pixels(small, truth);
  EXPECT_EQ(s.true_positive, 4u);
  EXPECT_EQ(s.false_positive, 0u);
  EXPECT_EQ(s.false_negative, 4u);
}

TEST(MaskMetrics, RejectsBadInputs) {
  const cv::Mat truth = rect_mask(0, 0, 2, 2);
  EXPECT_THROW(count_mask_pixels(truth, cv::Mat()), std::invalid_argument);
  EXPECT_THROW(count_mask_pixels(cv::Mat::zeros(4, 4, CV_32FC1), truth), std::invalid_argument);
  EXPECT_THROW(count_mask_pixels(truth, truth, cv::Mat::zeros(3, 4, CV_8UC1)),
               std::invalid_argument);
}

TEST(MaskMetrics, SequenceSummary) {
  MaskAccumulator acc;
  const cv::Mat truth = rect_mask(0, 0, 2, 4);
  acc.add(count_mask_pixels(truth, truth));         // IoU 1, 8 TP
  acc.add(count_mask_pixels(cv::Mat(), truth));     // IoU 0 (nothing predicted), 8 FN
  acc.add(count_mask_pixels(rect_mask(0, 0, 1, 1),  // static frame: 1 FP
                            cv::Mat::zeros(4, 4, CV_8UC1)));
  acc.add(count_mask_pixels(cv::Mat(), cv::Mat::zeros(4, 4, CV_8UC1)));  // static, clean
  const MaskSummary s = acc.summary();
  EXPECT_EQ(s.frames, 4u);
  EXPECT_EQ(s.dynamic_frames, 2u);
  EXPECT_DOUBLE_EQ(s.mean_iou, 0.5);         // over the two dynamic frames only
  EXPECT_DOUBLE_EQ(s.precision, 8.0 / 9.0);  // 8 TP, 1 FP over all frames
  EXPECT_DOUBLE_EQ(s.recall, 8.0 / 16.0);    // 8 TP, 8 FN
  EXPECT_EQ(s.static_frames, 2u);
  EXPECT_EQ(s.static_false_positive, 1u);
  EXPECT_EQ(s.static_frames_with_false_positives, 1u);
  const nlohmann::json j = to_json(s);
  EXPECT_DOUBLE_EQ(j["mean_iou"].get<double>(), 0.5);
  EXPECT_EQ(j["fn_px"].get<int>(), 8);

  const MaskSummary none = MaskAccumulator().summary();
  EXPECT_TRUE(std::isnan(none.mean_iou));
  EXPECT_TRUE(to_json(none)["precision"].is_null());
}

nlohmann::json fake_summary(double ate_rmse, double rpe_rot_mean) {
  nlohmann::json s;
  s["frames_processed"] = 10;
  s["statistics"] = {{"frames_tracked", 9}, {"frames_lost", 1}};
  s["evaluation"]["ate"] = {{"rmse_m", ate_rmse},
                            {"mean_m", 0.5 * ate_rmse},
                            {"median_m", 0.4 * ate_rmse},
                            {"std_m", nullptr}};
  s["evaluation"]["rpe"] = {{"trans_rmse_m_per_s", 1.0}, {"rot_mean_deg_per_s", rpe_rot_mean}};
  s["evaluation"]["tracked_ratio"] = 0.9;
  return s;
}

TEST(BenchmarkTables, ImprovementAsInThePaper) {
  EXPECT_DOUBLE_EQ(improvement_percent(0.5, 0.1), 80.0);
  EXPECT_DOUBLE_EQ(improvement_percent(0.1, 0.2), -100.0);  // worse: negative
  EXPECT_TRUE(std::isnan(improvement_percent(0.0, 0.1)));
  EXPECT_TRUE(std::isnan(improvement_percent(std::nan(""), 0.1)));

  nlohmann::json ours = fake_summary(0.02, 3.0);
  ours["masks"]["combined"] = {
      {"mean_iou", 0.75}, {"precision", 0.9}, {"recall", 0.8}, {"frames", 10}};
  const std::vector<BenchmarkRow> rows = {{"seq_a", ours, fake_summary(0.1, 4.0)}};
  const nlohmann::json t = benchmark_tables(rows, {{"mode", "deterministic"}}, nullptr);
  const nlohmann::json& ate = t["ate"]["rows"][0];
  EXPECT_EQ(ate["sequence"], "seq_a");
  EXPECT_DOUBLE_EQ(ate["baseline"]["rmse"].get<double>(), 0.1);
  EXPECT_DOUBLE_EQ(ate["ours"]["rmse"].get<double>(), 0.02);
  EXPECT_NEAR(ate["improvement_pct"]["rmse"].get<double>(), 80.0, 1e-9);
  EXPECT_TRUE(ate["improvement_pct"]["std"].is_null());  // missing statistic: no improvement
  EXPECT_NEAR(t["rpe_rotation"]["rows"][0]["improvement_pct"]["mean"].get<double>(), 25.0, 1e-9);
  EXPECT_DOUBLE_EQ(t["rpe_translation"]["rows"][0]["improvement_pct"]["rmse"].get<double>(), 0.0);
  ASSERT_EQ(t["masks"].size(), 1u);
  EXPECT_DOUBLE_EQ(t["masks"][0]["combined"]["mean_iou"].get<double>(), 0.75);
  EXPECT_EQ(t["tracking"][0]["ours"]["frames_tracked"], 9);
  EXPECT_TRUE(t["skipped"].is_array());

  const std::string md = benchmark_tables_markdown(t);
  EXPECT_NE(md.find("| seq_a | 0.1000 | 0.0500 | 0.0400 | - | 0.0200 | 0.0100 | 0.00800 | - | "
                    "80.00% | 80.00% | 80.00% | - |"),
            std::string::npos)
      << md;
  // Sub-millimetre errors keep three significant digits (they showed as 0.0009 and 0.0008 beside
  // an improvement of 17.4% that those numbers could not give).
  const std::vector<BenchmarkRow> small = {
      {"seq_b", fake_summary(0.000712, 3.0), fake_summary(0.000862, 4.0)}};
  const std::string small_md =
      benchmark_tables_markdown(benchmark_tables(small, {{"mode", "deterministic"}}, nullptr));
  EXPECT_NE(small_md.find("| seq_b | 0.000862 |"), std::string::npos) << small_md;
  EXPECT_NE(small_md.find("| 0.000712 |"), std::string::npos) << small_md;
  EXPECT_NE(md.find("Table 3"), std::string::npos);
}

}  // namespace
}  // namespace ddl::eval
