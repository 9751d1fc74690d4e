#pragma once
// Runs the System over a whole dataset and writes every output of a run into one folder:
//   CameraTrajectory.txt    TUM format, T_w_c of every tracked frame
//   KeyFrameTrajectory.txt  TUM format, T_w_c of every keyframe at the end of the run
//   summary.json            counters, per-stage timing medians, evaluation (when ground truth),
//                           mask quality (with RunOptions::mask_evaluator)
//   config.yaml             the effective configuration (written by the caller, see apps)
//   eval/                   ATE/RPE JSON and plots when the dataset has ground truth
//   the sparse map          where RunOptions::save_map_path says (docs/map-files.md)
// Outputs are written also when the run stops early (Ctrl-C through `stop`, or an error in a
// frame): the trajectory so far is flushed before the error propagates.

#include <atomic>
#include <functional>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>

#include "ddl/io/dataset_reader.h"
#include "ddl/pipeline/mask_evaluator.h"
#include "ddl/pipeline/system.h"

namespace ddl::pipeline {

struct RunOptions {
  std::string output_dir = "out/run";  // created if missing
  std::size_t first_frame = 0;         // skip frames before this index
  std::size_t max_frames = 0;          // 0 = all frames
  bool evaluate = true;                // evaluate against ground truth when the dataset has it
  /// > 0: frames are fed at this multiple of the camera's pace, as a live camera would deliver
  /// them (1 = real time; FramePacer); 0: as fast as the pipeline takes them.
  double playback_rate = 0.0;
  /// Paced runs only: keep the newest frame only, as a live camera with a one-frame buffer does
  /// (FramePrefetcher; the segmentation stage then holds one frame ahead of tracking): latency
  /// stays bounded, which frames are dropped depends on timing.
  bool drop_late_frames = false;
  /// Non-empty: the sparse map to start in (System::load_map), loaded before the first frame,
  /// before any output is written or removed.
  std::string load_map_path;
  /// Non-empty: where the sparse map is written at the end (System::save_map), also when the
  /// run is interrupted or fails in a frame; summary["sparse_map"] names it (absolute path).
  std::string save_map_path;
  /// When set and dynamic removal is on: fed every frame's masks; its JSON becomes
  /// summary["masks"] (MaskEvaluator::open gives one for sequences with ground-truth masks).
  MaskEvaluator* mask_evaluator = nullptr;
  /// When set: called from the calling thread with every frame and what process() reported
  /// (a viewer, say). Returning false stops the run after that frame, like `stop`.
  std::function<bool(const io::RgbdFrame&, const FrameOutcome&)> on_frame;
  /// When set: called once every option has been found valid, before the earlier run's listed
  /// outputs are removed and before the first frame (the caller's own outputs, such as the
  /// effective configuration, so that a run refused at its start leaves the folder as it was, and
  /// one whose setup output cannot be written keeps the earlier run's outputs).
  std::function<void()> on_start;
};

struct RunOutcome {
  bool interrupted = false;
  SystemStatistics statistics;
  nlohmann::json summary;  // what summary.json holds
};

/// `progress(done, total, note)` is called after every frame from the calling thread.
using ProgressFn = std::function<void(std::size_t, std::size_t, const std::string&)>;

/// Throws ddl::Interrupted, with nothing written or removed, when `stop` is already set before
/// the first frame.
RunOutcome run_sequence(const io::DatasetReader& dataset, System& system, const RunOptions& options,
                        const std::atomic<bool>* stop = nullptr, const ProgressFn& progress = {});

/// Timing summary as JSON: {stage: {count, median_ms, mean_ms, p90_ms, max_ms}}.
nlohmann::json timings_to_json(const TimingStats& timings);

}  // namespace ddl::pipeline
