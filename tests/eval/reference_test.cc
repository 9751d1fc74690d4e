// The acceptance test: the TUM scripts' own numbers for a real ORB-SLAM2 run on fr1_rpy
// (shared/reference/eval/*.expected.json) must be reproduced to 1e-6, by the library and by the
// `ddl_slam eval` binary.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <nlohmann/json.hpp>
#include <opencv2/imgcodecs.hpp>

#include "ddl/eval/evaluate.h"
#include "ddl/eval/report.h"
#include "eval_test_support.h"

namespace ddl::eval {
namespace {

using nlohmann::json;
namespace fs = std::filesystem;

constexpr double kTolerance = 1e-6;

bool reference_present() {
  return fs::exists(test::reference_groundtruth()) && fs::exists(test::reference_estimate()) &&
         fs::exists(test::reference_expected_json());
}

json load_expected() {
  std::ifstream file(test::reference_expected_json());
  return json::parse(file);
}

// Every numeric field of the expected "ate" and "rpe" sections must exist in `actual` under the
// same key and agree to kTolerance. Returns how many numbers were compared.
int expect_matches_reference(const json& expected, const json& actual) {
  int compared = 0;
  for (const char* section : {"ate", "rpe"}) {
    SCOPED_TRACE(section);
    EXPECT_TRUE(expected.contains(section));
    if (!expected.contains(section)) continue;
    for (const auto& [key, value] : expected[section].items()) {
      if (!value.is_number()) continue;
      SCOPED_TRACE(key);
      const bool present = actual.contains(section) && actual[section].contains(key) &&
                           actual[section][key].is_number();
      EXPECT_TRUE(present) << "missing numeric key " << section << "." << key;
      if (!present) continue;
      EXPECT_NEAR(actual[section][key].get<double>(), value.get<double>(), kTolerance);
      ++compared;
    }
  }
  return compared;
}

TEST(ReferenceTest, ReproducesTumScriptsOnFr1RpyOrbSlam2Run) {
  if (!reference_present())
    GTEST_SKIP() << "shared reference files absent under " << test::shared_dir();
  EvalInputs inputs;
  inputs.groundtruth_path = test::reference_groundtruth().string();
  inputs.estimate_path = test::reference_estimate().string();
  const EvalResult result = evaluate(inputs);
  const json expected = load_expected();
  const int compared = expect_matches_reference(expected, to_json(result));
  // 8 ATE numbers and 8 RPE numbers in the reference file today; all must have been checked.
  EXPECT_GE(compared, 16);

  // Direct checks of the library structs too (not only through the JSON writer).
  EXPECT_EQ(result.ate.est_poses, expected["ate"]["est_poses"].get<std::size_t>());
  EXPECT_EQ(result.ate.stats_m.count, expected["ate"]["compared_pose_pairs"].get<std::size_t>());
  EXPECT_NEAR(result.ate.stats_m.rmse, expected["ate"]["rmse_m"].get<double>(), kTolerance);
  EXPECT_EQ(result.rpe.trans_m.count, expected["rpe"]["compared_pose_pairs"].get<std::size_t>());
  EXPECT_NEAR(result.rpe.rot_deg.median, expected["rpe"]["rot_median_deg_per_s"].get<double>(),
              kTolerance);
  // Rigid alignment: a proper rotation, scale exactly 1.
  EXPECT_NEAR(result.ate.alignment.R_gt_est.determinant(), 1.0, 1e-12);
  EXPECT_EQ(result.ate.alignment.scale, 1.0);
}

TEST(ReferenceTest, TrackedRatioWithAssociations) {
  if (!reference_present() || !fs::exists(test::reference_associations())) {
    GTEST_SKIP() << "shared reference files absent under " << test::shared_dir();
  }
  EvalInputs inputs;
  inputs.groundtruth_path = test::reference_groundtruth().string();
  inputs.estimate_path = test::reference_estimate().string();
  inputs.frames_path = test::reference_associations().string();
  const EvalResult result = evaluate(inputs);
  ASSERT_TRUE(result.tracked.has_value());
  // The shared README: 694 associated frames, all tracked by this ORB-SLAM2 run.
  EXPECT_EQ(result.tracked->frames_total, 694u);
  EXPECT_EQ(result.tracked->tracked_frames, result.tracked->frames_in_gt_span);
  EXPECT_DOUBLE_EQ(result.tracked->ratio, 1.0);
}

int run_shell(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST(ReferenceTest, CliWritesJsonAndPlotsThatMatchTheReference) {
  if (!reference_present())
    GTEST_SKIP() << "shared reference files absent under " << test::shared_dir();
  const test::TempDir dir("cli_reference");
  const std::string json_path = dir.file("out/eval.json");
  const std::string plots = dir.file("plots");
  const std::string command = std::string("'") + DDL_SLAM_BINARY + "' eval --gt '" +
                              test::reference_groundtruth().string() + "' --est '" +
                              test::reference_estimate().string() + "' --json '" + json_path +
                              "' --plot-dir '" + plots + "' > '" + dir.file("stdout.txt") +
                              "' 2> '" + dir.file("stderr.txt") + "'";
  ASSERT_EQ(run_shell(command), 0) << test::read_text(dir.file("stderr.txt"));

  std::ifstream file(json_path);
  ASSERT_TRUE(file.good()) << json_path;
  const json actual = json::parse(file);
  EXPECT_GE(expect_matches_reference(load_expected(), actual), 16);
  EXPECT_FALSE(actual["tracked"]["available"].get<bool>());
  EXPECT_TRUE(actual["tracked"]["ratio"].is_null());
  EXPECT_EQ(actual["alignment"]["rotation"].size(), 3u);
  EXPECT_EQ(actual["alignment"]["scale"].get<double>(), 1.0);

  // The table on stdout shows the ATE RMSE.
  const std::string out = test::read_text(dir.file("stdout.txt"));
  EXPECT_NE(out.find("0.019887"), std::string::npos) << out;

  for (const char* name : {"trajectory_xy", "ate_over_time", "rpe_over_time"}) {
    const std::string stem = plots + "/" + name;
    const cv::Mat png = cv::imread(stem + ".png");
    EXPECT_FALSE(png.empty()) << stem << ".png";
    EXPECT_EQ(test::read_text(stem + ".svg").rfind("<svg", 0), 0u) << stem << ".svg";
  }
}

}  // namespace
}  // namespace ddl::eval
