// run_sequence: its per-frame callback sees every processed frame with its outcome, and returning
// false stops the run like Ctrl-C, with the outputs so far written; its summary times each stage.

#include "ddl/pipeline/sequence_runner.h"

#include <fmt/format.h>
#include <gtest/gtest.h>

#include <chrono>
#include <filesystem>
#include <fstream>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "ddl/core/error.h"
#include "ddl/io/dataset_reader.h"
#include "ddl/io/trajectory_io.h"
#include "ddl/pipeline/frame_pacer.h"
#include "ddl/pipeline/system.h"
#include "pipeline_test_support.h"

namespace ddl::pipeline {
namespace {
namespace fs = std::filesystem;

// Frames rendered in memory, served as a dataset.
class MemoryDataset final : public io::DatasetReader {
 public:
  MemoryDataset(const synthetic::SequenceSource& source) : camera_(source.camera()) {
    for (std::size_t i = 0; i < source.frame_count(); ++i) {
      io::RgbdFrame frame = testing::to_rgbd(source.render_frame(i), camera_);
      frame.index = i;
      frames_.push_back(std::move(frame));
    }
  }
  std::size_t size() const override { return frames_.size(); }
  double timestamp(std::size_t i) const override { return frames_.at(i).timestamp_s; }
  io::RgbdFrame frame(std::size_t i) const override { return frames_.at(i); }
  const camera::PinholeCamera& camera() const override { return camera_; }
  std::optional<std::string> groundtruth_path() const override { return groundtruth_path_; }
  void set_groundtruth_path(const std::string& path) { groundtruth_path_ = path; }
  std::string name() const override { return name_; }
  void set_name(const std::string& name) { name_ = name; }
  /// Frame i as a covered sensor shows it: black, no depth.
  void blank(std::size_t i) {
    frames_.at(i).rgb.setTo(cv::Scalar::all(0));
    frames_.at(i).depth_m.setTo(0.0f);
  }
  cv::Mat source_area() const override { return source_area_; }
  void set_source_area(const cv::Mat& area) { source_area_ = area; }

 private:
  camera::PinholeCamera camera_;
  std::vector<io::RgbdFrame> frames_;
  cv::Mat source_area_;
  std::string name_ = "memory";
  std::optional<std::string> groundtruth_path_;
};

std::size_t pose_lines(const fs::path& trajectory) {
  std::ifstream file(trajectory);
  std::size_t lines = 0;
  for (std::string line; std::getline(file, line);) lines += !line.empty() && line[0] != '#';
  return lines;
}

// Options of a run into `out`, emptied first, without the evaluation.
RunOptions fresh_run_options(const fs::path& out) {
  fs::remove_all(out);
  RunOptions options;
  options.output_dir = out.string();
  options.evaluate = false;
  return options;
}

TEST(SequenceRunner, TheFrameCallbackSeesEveryFrameAndCanStopTheRun) {
  const auto vocabulary = testing::default_vocabulary();
  if (!vocabulary) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const auto source = synthetic::make_sequence_source(testing::preset_config("syn_static_xyz", 20));
  const MemoryDataset dataset(*source);
  const fs::path out = fs::path(::testing::TempDir()) / "sequence_runner_callback";
  System system(testing::core_config(), dataset.camera(), vocabulary);
  RunOptions options = fresh_run_options(out);
  std::vector<std::size_t> seen;
  std::size_t matched_keypoints = 0;
  options.on_frame = [&](const io::RgbdFrame& frame, const FrameOutcome& outcome) {
    seen.push_back(frame.index);
    EXPECT_EQ(outcome.tracking.keypoints.size(), outcome.tracking.num_features);
    for (const tracking::KeypointStatus& k : outcome.tracking.keypoints)
      matched_keypoints += k.matched;
    return frame.index < 7;  // stop after frame 7
  };
  const RunOutcome outcome = run_sequence(dataset, system, options);
  EXPECT_TRUE(outcome.interrupted);
  EXPECT_TRUE(outcome.summary["interrupted"].get<bool>());
  EXPECT_EQ(seen, (std::vector<std::size_t>{0, 1, 2, 3, 4, 5, 6, 7}));
  EXPECT_GT(matched_keypoints, 7u * 100u);  // frames 1-7 track against the map
  // The frames processed before the stop are written.
  EXPECT_EQ(pose_lines(out / "CameraTrajectory.txt"), 8u);
  fs::remove_all(out);
}

// Every keyframe's local mapping is timed as a whole and stage by stage; the stages lie within
// the whole.
// The picture veto learns from the dataset where the sensor's image lies: the blank margin of a
// distorted camera's undistorted frames is no depth hole (docs/dynamics.md, "Pictures").
TEST(SequenceRunner, TheDynamicFrontEndGetsTheDatasetsSourceArea) {
  const auto vocabulary = testing::default_vocabulary();
  if (!vocabulary) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const auto source = synthetic::make_sequence_source(testing::preset_config("syn_static_xyz", 3));
  MemoryDataset dataset(*source);
  const camera::PinholeCamera& camera = dataset.camera();
  cv::Mat area(camera.height, camera.width, CV_8UC1, cv::Scalar(0));
  area(cv::Rect(10, 10, camera.width - 20, camera.height - 20)).setTo(255);
  dataset.set_source_area(area);
  System system(testing::core_config(), camera, vocabulary);
  ASSERT_TRUE(system.dynamic_front_end().source_area().empty());
  run_sequence(dataset, system,
               fresh_run_options(fs::path(::testing::TempDir()) / "sequence_runner_area"));
  EXPECT_EQ(cv::norm(system.dynamic_front_end().source_area(), area, cv::NORM_INF), 0.0);
}

// An output that cannot be written (here a folder stands where the camera trajectory goes) does
// not stop the others: summary.json lists it under output_errors and says the run failed, which
// then ends with an OutputError naming the file. A dataset name that is not UTF-8 reaches
// summary.json with U+FFFD in place of its bad byte instead of emptying the file.
TEST(SequenceRunner, AnOutputThatCannotBeWrittenFailsTheRunAfterTheOthers) {
  const auto vocabulary = testing::default_vocabulary();
  if (!vocabulary) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const auto source = synthetic::make_sequence_source(testing::preset_config("syn_static_xyz", 5));
  MemoryDataset dataset(*source);
  dataset.set_name("caf\xe9");
  const fs::path out = fs::path(::testing::TempDir()) / "sequence_runner_output_error";
  const RunOptions options = fresh_run_options(out);
  fs::create_directories(out / "CameraTrajectory.txt");
  System system(testing::core_config(), dataset.camera(), vocabulary);
  try {
    run_sequence(dataset, system, options);
    ADD_FAILURE() << "the run did not fail";
  } catch (const OutputError& e) {
    EXPECT_NE(std::string(e.what()).find("CameraTrajectory.txt"), std::string::npos) << e.what();
  }
  std::ifstream file(out / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(file);
  EXPECT_TRUE(summary.at("failed").get<bool>());
  ASSERT_EQ(summary.at("output_errors").size(), 1u);
  EXPECT_FALSE(summary.at("outputs").contains("camera_trajectory"));
  EXPECT_EQ(summary.at("outputs").at("keyframe_trajectory"), "KeyFrameTrajectory.txt");
  EXPECT_GT(pose_lines(out / "KeyFrameTrajectory.txt"), 0u);
  EXPECT_EQ(summary.at("sequence").get<std::string>(), "caf\xef\xbf\xbd");
  EXPECT_FALSE(fs::exists(out / "CameraTrajectory.txt.partial"));
}

// A run into a folder that holds an earlier run's outputs removes the files that run's summary
// listed (here an evaluation and a map this run does not write), and nothing outside the folder.
TEST(SequenceRunner, AnEarlierRunsListedOutputsAreRemoved) {
  const auto vocabulary = testing::default_vocabulary();
  if (!vocabulary) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const auto source = synthetic::make_sequence_source(testing::preset_config("syn_static_xyz", 3));
  const MemoryDataset dataset(*source);
  const fs::path root = fs::path(::testing::TempDir()) / "sequence_runner_earlier";
  fs::remove_all(root);
  const fs::path out = root / "run";
  fs::create_directories(out / "eval");
  for (const fs::path& f :
       {out / "eval" / "eval.json", out / "map.ot", out / "notes.txt", root / "outside.txt"}) {
    std::ofstream(f) << "earlier";
  }
  // A listed symbolic link stays a link; the new run writes into its target.
  std::ofstream(root / "kept_trajectory.txt") << "earlier";
  fs::create_symlink(root / "kept_trajectory.txt", out / "CameraTrajectory.txt");
  std::ofstream(out / "summary.json")
      << nlohmann::json{{"outputs",
                         {{"map", {"map.ot"}},
                          {"evaluation", {"eval/eval.json"}},
                          {"camera_trajectory", "CameraTrajectory.txt"},
                          {"other", {"../outside.txt", (root / "outside.txt").string()}}}}}
             .dump();
  RunOptions options;
  options.output_dir = out.string();
  options.evaluate = false;
  System system(testing::core_config(), dataset.camera(), vocabulary);
  // A bad option ends the run before it starts: the earlier outputs stay, and the caller's own
  // outputs (on_start: cmd_run's config.yaml) are not written.
  int starts = 0;
  options.on_start = [&] {
    ++starts;
    EXPECT_TRUE(fs::exists(out / "map.ot")) << "called after the earlier outputs went";
  };
  options.first_frame = 100;
  EXPECT_THROW(run_sequence(dataset, system, options), ConfigError);
  EXPECT_TRUE(fs::exists(out / "map.ot"));
  EXPECT_TRUE(fs::exists(out / "summary.json"));
  EXPECT_EQ(starts, 0);
  // A setup output that cannot be written ends the run with the earlier outputs kept.
  options.first_frame = 0;
  options.on_start = [&] { throw OutputError::at("config.yaml", "cannot write"); };
  EXPECT_THROW(run_sequence(dataset, system, options), OutputError);
  EXPECT_TRUE(fs::exists(out / "map.ot"));
  // Ctrl-C before the first frame (while the models loaded): nothing ran, nothing is removed
  // (review, stop 25).
  options.on_start = [&] { ++starts; };
  const std::atomic<bool> stopped{true};
  EXPECT_THROW(run_sequence(dataset, system, options, &stopped), Interrupted);
  EXPECT_TRUE(fs::exists(out / "map.ot"));
  EXPECT_EQ(starts, 0);
  options.on_start = [&] {
    ++starts;
    EXPECT_TRUE(fs::exists(out / "map.ot")) << "called after the earlier outputs went";
  };
  options.first_frame = 0;
  run_sequence(dataset, system, options);
  EXPECT_EQ(starts, 1);
  EXPECT_FALSE(fs::exists(out / "eval" / "eval.json"));
  EXPECT_FALSE(fs::exists(out / "map.ot"));
  EXPECT_TRUE(fs::exists(out / "notes.txt")) << "not listed, not ours";
  EXPECT_TRUE(fs::exists(root / "outside.txt")) << "outside the folder";
  EXPECT_TRUE(fs::is_symlink(out / "CameraTrajectory.txt"));
  EXPECT_EQ(pose_lines(root / "kept_trajectory.txt"), 3u);
  std::ifstream file(out / "summary.json");
  EXPECT_FALSE(nlohmann::json::parse(file).at("outputs").contains("evaluation"));
}

// The evaluation's report is an output too: failing to write it fails the run (exit code 1), and
// the evaluation itself is still in summary.json.
TEST(SequenceRunner, AnEvaluationReportThatCannotBeWrittenFailsTheRun) {
  const auto vocabulary = testing::default_vocabulary();
  if (!vocabulary) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const auto source = synthetic::make_sequence_source(testing::preset_config("syn_static_xyz", 45));
  MemoryDataset dataset(*source);
  const fs::path root = fs::path(::testing::TempDir()) / "sequence_runner_eval_output";
  fs::remove_all(root);
  io::write_tum_trajectory((root / "groundtruth.txt").string(), source->groundtruth());
  dataset.set_groundtruth_path((root / "groundtruth.txt").string());
  const fs::path out = root / "run";
  fs::create_directories(out / "eval" / "eval.json");  // a folder in the report's place
  RunOptions options;
  options.output_dir = out.string();
  System system(testing::core_config(), dataset.camera(), vocabulary);
  EXPECT_THROW(run_sequence(dataset, system, options), OutputError);
  std::ifstream file(out / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(file);
  EXPECT_TRUE(summary.at("failed").get<bool>());
  ASSERT_EQ(summary.at("output_errors").size(), 1u);
  EXPECT_NE(summary["output_errors"][0].get<std::string>().find("eval.json"), std::string::npos);
  EXPECT_TRUE(summary.contains("evaluation"));
  EXPECT_EQ(summary.at("outputs").at("evaluation").size(), 6u) << "the six plots";
}

// The pictures a run writes frame by frame are outputs too: a mask that cannot be written (here a
// folder stands in its place) lets the run go on and write the other masks, then fails it with an
// error that counts the failures and names the first, listed in summary.json.
TEST(SequenceRunner, ASavedMaskThatCannotBeWrittenFailsTheRunAfterTheOthers) {
  const auto vocabulary = testing::default_vocabulary();
  if (!vocabulary) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const auto source = synthetic::make_sequence_source(testing::preset_config("syn_walking_xyz", 4));
  const MemoryDataset dataset(*source);
  const fs::path out = fs::path(::testing::TempDir()) / "sequence_runner_mask_error";
  const RunOptions options = fresh_run_options(out);
  SystemConfig config = testing::core_config();
  config.dynamic.enabled = true;
  config.dynamic.segmentation.backend = segmentation::Backend::kNone;
  config.save_masks = true;
  config.output_dir = out.string();
  const std::string blocked = fmt::format("{:.6f}.png", dataset.timestamp(2));
  fs::create_directories(out / "masks" / blocked);
  System system(config, dataset.camera(), vocabulary);
  try {
    run_sequence(dataset, system, options);
    ADD_FAILURE() << "the run did not fail";
  } catch (const OutputError& e) {
    // The combined mask and its parts count alike; only frame 2's combined mask failed.
    EXPECT_EQ(std::string(e.what()).rfind("1 of ", 0), 0u) << e.what();
    EXPECT_NE(std::string(e.what()).find("files of the saved masks"), std::string::npos)
        << e.what();
    EXPECT_NE(std::string(e.what()).find(blocked), std::string::npos) << e.what();
  }
  for (std::size_t i : {0, 1, 3}) {
    EXPECT_TRUE(
        fs::is_regular_file(out / "masks" / fmt::format("{:.6f}.png", dataset.timestamp(i))))
        << "frame " << i;
  }
  std::ifstream file(out / "summary.json");
  const nlohmann::json summary = nlohmann::json::parse(file);
  EXPECT_TRUE(summary.at("failed").get<bool>());
  ASSERT_EQ(summary.at("output_errors").size(), 1u);
  EXPECT_EQ(pose_lines(out / "CameraTrajectory.txt"), 4u);
}

// Tracking lost while the map is young resets it, which drops the poses before the reset: the
// summary's `poses` counts what the trajectory holds, `frames_tracked` what was tracked.
TEST(SequenceRunner, ThePosesCountTheTrajectoryAfterAMapReset) {
  const auto vocabulary = testing::default_vocabulary();
  if (!vocabulary) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const auto source = synthetic::make_sequence_source(testing::preset_config("syn_static_xyz", 24));
  MemoryDataset dataset(*source);
  for (std::size_t i = 8; i < 12; ++i) dataset.blank(i);
  const fs::path out = fs::path(::testing::TempDir()) / "sequence_runner_reset";
  System system(testing::core_config(), dataset.camera(), vocabulary);
  const RunOutcome outcome = run_sequence(dataset, system, fresh_run_options(out));
  ASSERT_GE(outcome.statistics.map_resets, 1u);
  EXPECT_EQ(outcome.statistics.poses, pose_lines(out / "CameraTrajectory.txt"));
  EXPECT_LT(outcome.statistics.poses, outcome.statistics.frames_tracked);
  std::ifstream file(out / "summary.json");
  EXPECT_EQ(nlohmann::json::parse(file).at("statistics").at("poses").get<std::size_t>(),
            outcome.statistics.poses);
}

TEST(SequenceRunner, TheSummaryTimesLocalMappingStageByStage) {
  const auto vocabulary = testing::default_vocabulary();
  if (!vocabulary) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const auto source = synthetic::make_sequence_source(testing::preset_config("syn_static_xyz", 40));
  const MemoryDataset dataset(*source);
  const fs::path out = fs::path(::testing::TempDir()) / "sequence_runner_timings";
  System system(testing::core_config(), dataset.camera(), vocabulary);
  RunOptions options = fresh_run_options(out);
  const RunOutcome outcome = run_sequence(dataset, system, options);
  const nlohmann::json& timing = outcome.summary["timing_ms"];
  ASSERT_TRUE(timing.contains("local_mapping")) << timing.dump();
  const auto keyframes = timing["local_mapping"]["count"].get<std::size_t>();
  EXPECT_GE(keyframes, 2u);
  double stages_ms = 0.0;  // summed over the keyframes
  for (const char* stage :
       {"insertion", "point_culling", "triangulation", "fusion", "local_ba", "keyframe_culling"}) {
    const std::string key = std::string("local_mapping.") + stage;
    ASSERT_TRUE(timing.contains(key)) << key;
    const auto count = timing[key]["count"].get<std::size_t>();
    // Local BA waits for enough keyframes; nothing aborts a stage in deterministic mode.
    if (std::string(stage) == "local_ba") {
      EXPECT_GE(count, 1u);
      EXPECT_LT(count, keyframes);
    } else {
      EXPECT_EQ(count, keyframes) << key;
    }
    stages_ms += timing[key]["mean_ms"].get<double>() * static_cast<double>(count);
  }
  EXPECT_GT(timing["local_mapping.local_ba"]["mean_ms"].get<double>(), 0.0);
  EXPECT_LE(stages_ms,
            timing["local_mapping"]["mean_ms"].get<double>() * static_cast<double>(keyframes));
  fs::remove_all(out);
}

// A paced run takes at least the span of its stamps over the rate, records each frame's latency
// and, in deterministic mode, gives the trajectory of the run that was not paced.
TEST(SequenceRunner, APacedRunFollowsTheStampsAndKeepsTheTrajectory) {
  const auto vocabulary = testing::default_vocabulary();
  if (!vocabulary) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const auto source = synthetic::make_sequence_source(testing::preset_config("syn_static_xyz", 20));
  const MemoryDataset dataset(*source);
  const double span_s = dataset.timestamp(19) - dataset.timestamp(0);
  ASSERT_GT(span_s, 0.5);
  const fs::path out = fs::path(::testing::TempDir()) / "sequence_runner_paced";
  auto run = [&](double rate, const std::string& name) {
    System system(testing::core_config(), dataset.camera(), vocabulary);
    RunOptions options = fresh_run_options(out / name);
    options.playback_rate = rate;
    return run_sequence(dataset, system, options).summary;
  };
  const nlohmann::json fast = run(0.0, "fast");
  const nlohmann::json paced = run(2.0, "paced");
  EXPECT_TRUE(fast["playback_rate"].is_null());
  EXPECT_FALSE(fast["timing_ms"].contains("latency"));
  EXPECT_EQ(paced["playback_rate"].get<double>(), 2.0);
  EXPECT_GE(paced["wall_time_s"].get<double>(), span_s / 2.0);
  EXPECT_EQ(paced["timing_ms"]["latency"]["count"].get<std::size_t>(), 20u);
  auto read = [](const fs::path& path) {
    std::ifstream file(path);
    return std::string(std::istreambuf_iterator<char>(file), {});
  };
  EXPECT_EQ(read(out / "fast" / "CameraTrajectory.txt"),
            read(out / "paced" / "CameraTrajectory.txt"));
  fs::remove_all(out);
}

// A run stopped while the next frame is far from due ends at once: the pacing wait is cancelled
// before the stages that read from it are taken down.
TEST(SequenceRunner, AStoppedPacedRunDoesNotWaitForTheNextFrame) {
  const auto vocabulary = testing::default_vocabulary();
  if (!vocabulary) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const auto source = synthetic::make_sequence_source(testing::preset_config("syn_static_xyz", 4));
  const MemoryDataset dataset(*source);
  const fs::path out = fs::path(::testing::TempDir()) / "sequence_runner_paced_stop";
  System system(testing::core_config(), dataset.camera(), vocabulary);
  RunOptions options = fresh_run_options(out);
  options.playback_rate = FramePacer::kMinRate;  // frame 1 is due about 33 s after frame 0
  options.on_frame = [](const io::RgbdFrame&, const FrameOutcome&) { return false; };
  const auto start = std::chrono::steady_clock::now();
  const RunOutcome outcome = run_sequence(dataset, system, options);
  const double elapsed_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  EXPECT_TRUE(outcome.interrupted);
  EXPECT_EQ(outcome.summary["frames_processed"].get<std::size_t>(), 1u);
  EXPECT_LT(elapsed_s, 15.0);
  fs::remove_all(out);
}

}  // namespace
}  // namespace ddl::pipeline
