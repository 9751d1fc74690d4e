// Bad input gives a clear ddl::InputError / ConfigError naming the file (and line) and the problem;
// the CLI turns it into "error: ..." on stderr and exit code 2.

#include <gtest/gtest.h>
#include <sys/wait.h>

#include <cstdlib>
#include <string>

#include "config_error_check.h"
#include "ddl/core/error.h"
#include "ddl/eval/evaluate.h"
#include "ddl/eval/report.h"
#include "ddl/io/trajectory_io.h"
#include "eval_test_support.h"

namespace ddl::eval {
namespace {

std::string good_trajectory(double start, int n) {
  std::string s = "# timestamp tx ty tz qx qy qz qw\n";
  for (int k = 0; k < n; ++k) {
    const double t = start + k * 0.03125;
    s += fmt::format("{} {} {} 0.5 0 0 0 1\n", t, 0.1 * k, 0.01 * k * k);
  }
  return s;
}

// Runs evaluate() and returns the InputError message (fails the test if none is thrown).
std::string input_error_of(const EvalInputs& inputs, const EvalOptions& options = {}) {
  try {
    evaluate(inputs, options);
  } catch (const InputError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no InputError thrown";
  return {};
}

void expect_contains(const std::string& text, const std::string& part) {
  EXPECT_NE(text.find(part), std::string::npos) << "'" << part << "' not in: " << text;
}

class BadInputTest : public ::testing::Test {
 protected:
  BadInputTest() : dir_("bad_input") {
    inputs_.groundtruth_path = test::write_text(dir_.file("gt.txt"), good_trajectory(100.0, 80));
    inputs_.estimate_path = test::write_text(dir_.file("est.txt"), good_trajectory(100.0, 80));
  }
  test::TempDir dir_;
  EvalInputs inputs_;
};

TEST_F(BadInputTest, GoodFilesEvaluate) {
  const EvalResult r = evaluate(inputs_);
  EXPECT_EQ(r.ate.stats_m.count, 80u);
  EXPECT_LT(r.ate.stats_m.max, 1e-9);
}

TEST_F(BadInputTest, MalformedLineNamesFileAndLine) {
  test::write_text(inputs_.estimate_path, "# header\n100.0 0 0 0 0 0 0 1\n100.1 0 0 abc 0 0 0 1\n");
  const std::string msg = input_error_of(inputs_);
  expect_contains(msg, inputs_.estimate_path + ":3:");
  expect_contains(msg, "'abc' is not a number");
}

TEST_F(BadInputTest, WrongFieldCountNamesFileAndLine) {
  test::write_text(inputs_.groundtruth_path, "100.0 0 0 0 0 0 0 1\n100.1 0 0 0 0 0 1\n");
  const std::string msg = input_error_of(inputs_);
  expect_contains(msg, inputs_.groundtruth_path + ":2:");
  expect_contains(msg, "expected 8 values");
}

TEST_F(BadInputTest, MissingEstimateFile) {
  inputs_.estimate_path = dir_.file("nope.txt");
  const std::string msg = input_error_of(inputs_);
  expect_contains(msg, inputs_.estimate_path);
  expect_contains(msg, "file not found");
}

TEST_F(BadInputTest, MissingGroundTruthFile) {
  inputs_.groundtruth_path = dir_.file("no_groundtruth.txt");
  const std::string msg = input_error_of(inputs_);
  expect_contains(msg, inputs_.groundtruth_path);
  expect_contains(msg, "file not found");
}

TEST_F(BadInputTest, EmptyFile) {
  test::write_text(inputs_.estimate_path, "# only a comment\n\n");
  const std::string msg = input_error_of(inputs_);
  expect_contains(msg, inputs_.estimate_path);
  expect_contains(msg, "empty");
}

// Stamps out of order or repeated are read as TUM's evaluate_ate.py / evaluate_rpe.py read them
// (a dict keyed by stamp, then sorted): in time order, the last line of a repeated stamp kept.
TEST_F(BadInputTest, StampsOutOfOrderAreReadAsTheTumToolsReadThem) {
  test::write_text(inputs_.estimate_path,
                   "100.0 0 0 0 0 0 0 1\n100.2 2 0 0 0 0 0 1\n100.1 1 0 0 0 0 0 1\n"
                   "100.2 3 0 0 0 0 0 1\n");
  const io::Trajectory t = io::read_tum_trajectory(inputs_.estimate_path);
  ASSERT_EQ(t.size(), 3u);
  EXPECT_EQ(t[0].timestamp_s, 100.0);
  EXPECT_EQ(t[1].timestamp_s, 100.1);
  EXPECT_EQ(t[1].t_w_c.x(), 1.0);
  EXPECT_EQ(t[2].timestamp_s, 100.2);
  EXPECT_EQ(t[2].t_w_c.x(), 3.0) << "the last line of stamp 100.2";
}

TEST_F(BadInputTest, NoOverlappingStampsNamesBothFiles) {
  test::write_text(inputs_.estimate_path, good_trajectory(500.0, 80));
  const std::string msg = input_error_of(inputs_);
  expect_contains(msg, inputs_.estimate_path);
  expect_contains(msg, inputs_.groundtruth_path);
  expect_contains(msg, "only 0 ground-truth/estimate pose(s) associate");
}

TEST_F(BadInputTest, SingleOverlappingPoseIsNotEnough) {
  test::write_text(inputs_.estimate_path, "100.0 0 0 0.5 0 0 0 1\n300.0 0 0 0 0 0 0 1\n");
  const std::string msg = input_error_of(inputs_);
  expect_contains(msg, "only 1 ground-truth/estimate pose(s) associate");
}

// Coordinates so large that the squared errors overflow give no table: an error naming the files
// instead of an ATE of inf or nan.
TEST_F(BadInputTest, CoordinatesTooLargeToEvaluateAreAnError) {
  std::string s;
  for (int k = 0; k < 80; ++k) {
    s += fmt::format("{} {} 0 0 0 0 0 1\n", 100.0 + k * 0.03125, 1e300 * (k % 3));
  }
  test::write_text(inputs_.estimate_path, s);
  const std::string msg = input_error_of(inputs_);
  expect_contains(msg, inputs_.estimate_path);
  expect_contains(msg, "not finite");
}

// As evaluate_ate.py and evaluate_rpe.py, which are two programs: an estimate too short for the
// RPE delta still has its ATE, and the RPE says why it is missing (review, stop 24: both were
// dropped, so a short run had no ATE in the tables).
TEST_F(BadInputTest, EstimateShorterThanDeltaHasItsAteAndSaysWhyRpeIsMissing) {
  test::write_text(inputs_.estimate_path, good_trajectory(100.0, 20));  // 0.6 s < 1 s
  const EvalResult r = evaluate(inputs_, EvalOptions{});
  EXPECT_EQ(r.ate.stats_m.count, 20u);
  EXPECT_NEAR(r.ate.stats_m.rmse, 0.0, 1e-9);
  expect_contains(r.rpe_error, inputs_.estimate_path);
  expect_contains(r.rpe_error, "RPE");
  const nlohmann::json j = to_json(r);
  EXPECT_FALSE(j["rpe"]["available"].get<bool>());
  EXPECT_TRUE(j["rpe"]["trans_rmse_m_per_s"].is_null());
  EXPECT_TRUE(j["rpe"]["compared_pose_pairs"].is_null());
  expect_contains(format_report(r), "unavailable");
}

TEST_F(BadInputTest, MalformedFramesFileNamesFileAndLine) {
  inputs_.frames_path =
      test::write_text(dir_.file("rgb.txt"), "# rgb\n100.0 rgb/a.png\nhello rgb/b.png\n");
  const std::string msg = input_error_of(inputs_);
  expect_contains(msg, inputs_.frames_path + ":3:");
  inputs_.frames_path = dir_.file("missing_rgb.txt");
  expect_contains(input_error_of(inputs_), inputs_.frames_path);
  // A NaN stamp used to pass and break the de-duplication (a wrong tracked ratio).
  inputs_.frames_path =
      test::write_text(dir_.file("rgb_nan.txt"), "# rgb\n100.0 rgb/a.png\nnan rgb/b.png\n");
  const std::string nan_msg = input_error_of(inputs_);
  expect_contains(nan_msg, inputs_.frames_path + ":3:");
  expect_contains(nan_msg, "not finite");
  // A list of another sequence: no frame inside the ground truth's span (review, stop 32: it
  // printed "0 of 0 frames (nan %)" and exited 0).
  inputs_.frames_path =
      test::write_text(dir_.file("rgb_other.txt"), "# rgb\n500.0 rgb/a.png\n501.0 rgb/b.png\n");
  const std::string other_msg = input_error_of(inputs_);
  expect_contains(other_msg, inputs_.frames_path);
  expect_contains(other_msg, "ground truth's time span");
}

// --align-scale against an estimate that never moved: the scale is undefined, an input fault
// that names both files (it was a plain library error, exit code 1).
TEST_F(BadInputTest, ScaleAlignmentOfAStillEstimateNamesBothFiles) {
  std::string still;
  for (int k = 0; k < 80; ++k) still += fmt::format("{} 1 2 3 0 0 0 1\n", 100.0 + k * 0.03125);
  test::write_text(inputs_.estimate_path, still);
  EvalOptions o;
  o.align_scale = true;
  const std::string msg = input_error_of(inputs_, o);
  expect_contains(msg, inputs_.estimate_path);
  expect_contains(msg, inputs_.groundtruth_path);
  expect_contains(msg, "scale");
}

TEST_F(BadInputTest, BadOptionsNameTheKey) {
  EvalOptions o;
  o.rpe_delta = 0.0;
  EXPECT_TRUE(test_support::throws_config_error_for_key([&] { evaluate(inputs_, o); }, "delta"));
  o = {};
  o.max_difference_s = -1.0;
  EXPECT_THROW(evaluate(inputs_, o), ConfigError);
  EXPECT_THROW(parse_delta_unit("m"), ConfigError);
}

int run_shell(const std::string& command) {
  const int status = std::system(command.c_str());
  return WIFEXITED(status) ? WEXITSTATUS(status) : -1;
}

TEST_F(BadInputTest, CliReportsMissingFileWithExitCode2) {
  const std::string missing = dir_.file("missing_est.txt");
  const std::string err = dir_.file("stderr.txt");
  const int code =
      run_shell(std::string("'") + DDL_SLAM_BINARY + "' eval --gt '" + inputs_.groundtruth_path +
                "' --est '" + missing + "' > /dev/null 2> '" + err + "'");
  EXPECT_EQ(code, 2);
  const std::string text = test::read_text(err);
  EXPECT_EQ(text.rfind("error: ", 0), 0u) << text;
  expect_contains(text, missing);
}

TEST_F(BadInputTest, CliRejectsAnUnknownDeltaUnitWithExitCode2) {
  const int code =
      run_shell(std::string("'") + DDL_SLAM_BINARY + "' eval --gt '" + inputs_.groundtruth_path +
                "' --est '" + inputs_.estimate_path + "' --delta-unit m > /dev/null 2>&1");
  EXPECT_EQ(code, 2);
}

}  // namespace
}  // namespace ddl::eval
