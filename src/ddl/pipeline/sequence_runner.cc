#include "ddl/pipeline/sequence_runner.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <filesystem>
#include <fstream>
#include <functional>

#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"
#include "ddl/eval/evaluate.h"
#include "ddl/eval/plot.h"
#include "ddl/eval/report.h"
#include "ddl/eval/tracked.h"
#include "ddl/pipeline/frame_pacer.h"
#include "ddl/pipeline/frame_prefetcher.h"
#include "ddl/pipeline/segmentation_stage.h"

namespace ddl::pipeline {
namespace fs = std::filesystem;

nlohmann::json timings_to_json(const TimingStats& timings) {
  nlohmann::json out = nlohmann::json::object();
  for (const auto& [stage, s] : timings.summary()) {
    out[stage] = {{"count", s.count},
                  {"median_ms", s.median_ms},
                  {"mean_ms", s.mean_ms},
                  {"p90_ms", s.p90_ms},
                  {"max_ms", s.max_ms}};
  }
  return out;
}

namespace {

/// Removes the files an earlier run listed under "outputs" in `out_dir`/summary.json, so that a
/// shorter, interrupted or unevaluated run into the same folder leaves none of them behind (its
/// eval/ report and plots, its maps). Only names inside the folder are touched; an unreadable or
/// malformed summary removes nothing.
void remove_earlier_outputs(const fs::path& out_dir) {
  // Only regular files are read or removed: a symbolic link stays (its target is written into),
  // and a FIFO or device in summary.json's place is not read (it could block).
  const auto regular = [](const fs::path& path) {
    std::error_code ec;
    return fs::is_regular_file(fs::symlink_status(path, ec));
  };
  if (!regular(out_dir / "summary.json")) return;
  std::ifstream file(out_dir / "summary.json");
  if (!file) return;
  const nlohmann::json summary = nlohmann::json::parse(file, nullptr, false);
  if (summary.is_discarded() || !summary.contains("outputs")) return;
  std::vector<std::string> names;
  const std::function<void(const nlohmann::json&)> collect = [&](const nlohmann::json& j) {
    if (j.is_string()) names.push_back(j.get<std::string>());
    if (j.is_array() || j.is_object()) {
      for (const nlohmann::json& item : j) collect(item);
    }
  };
  collect(summary["outputs"]);
  for (const std::string& name : names) {
    const fs::path relative(name);
    if (relative.empty() || relative.is_absolute()) continue;
    bool inside = true;
    for (const fs::path& part : relative) inside = inside && part != "..";
    std::error_code ec;
    if (inside && regular(out_dir / relative)) fs::remove(out_dir / relative, ec);
  }
  std::error_code ec;
  fs::remove(out_dir / "summary.json", ec);  // it described them
}

/// Whole or not at all (core/filesystem.h); text that is not UTF-8 (a sequence folder's name, a
/// path in an error message) is written with U+FFFD in place of its bad bytes, not refused.
void write_json(const fs::path& path, const nlohmann::json& json) {
  write_file_atomically(path, "the run's summary",
                        json.dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + '\n');
}

nlohmann::json statistics_to_json(const SystemStatistics& s) {
  return {{"frames", s.frames},
          {"frames_tracked", s.frames_tracked},
          {"poses", s.poses},
          {"frames_lost", s.frames_lost},
          {"relocalizations", s.relocalizations},
          {"relocalizations_in_same_frame", s.relocalizations_in_same_frame},
          {"frames_with_motion_prior", s.frames_with_motion_prior},
          {"keyframes_created", s.keyframes_created},
          {"keyframes_loaded", s.keyframes_loaded},
          {"map_points_loaded", s.map_points_loaded},
          {"keyframe_depth_images_loaded", s.keyframe_depth_images_loaded},
          {"depth_images_aligned", s.depth_images_aligned},
          {"keyframes", s.keyframes},
          {"map_points", s.map_points},
          {"loops_closed", s.loops_closed},
          {"map_resets", s.map_resets},
          {"geometry_checks_low_cost", s.geometry_checks_low_cost},
          {"geometry_checks_predicted", s.geometry_checks_predicted},
          {"geometry_checks_implausible", s.geometry_checks_implausible},
          {"geometry_checks_skipped", s.geometry_checks_skipped},
          {"geometry_checks_without_reference", s.geometry_checks_without_reference},
          {"free_space_checks_skipped", s.free_space_checks_skipped},
          {"free_space_regions_dropped", s.free_space_regions_dropped},
          {"segmentations_turned", s.segmentations_turned},
          {"cnn_pictures_dropped", s.cnn_pictures_dropped},
          {"cnn_pictures_unjudged", s.cnn_pictures_unjudged},
          {"dense",
           {{"keyframes", s.dense.keyframes},
            {"masked_pixels", s.dense.masked_pixels},
            {"filled_pixels", s.dense.filled_pixels},
            {"image_filled_pixels", s.dense.image_filled_pixels},
            {"octree_rebuilds", s.dense.octree_rebuilds},
            {"scans_loaded", s.dense.scans_loaded},
            {"peak_stored_image_bytes", s.dense.peak_stored_image_bytes}}}};
}

}  // namespace

RunOutcome run_sequence(const io::DatasetReader& dataset, System& system, const RunOptions& options,
                        const std::atomic<bool>* stop, const ProgressFn& progress) {
  if (options.drop_late_frames && options.playback_rate <= 0.0) {
    throw ConfigError::for_key("--drop-late-frames", "needs --playback-rate (a paced run)");
  }
  // Any rate but 0 (NaN and negative included) goes to the pacer, which names what is wrong.
  std::optional<FramePacer> pacer;
  if (options.playback_rate != 0.0) pacer.emplace(options.playback_rate, stop);
  if (options.drop_late_frames && system.config().mode == RunMode::kDeterministic) {
    spdlog::warn(
        "--drop-late-frames: which frames are dropped depends on timing, so this deterministic "
        "run will not reproduce its trajectory");
  }
  const fs::path out_dir(options.output_dir);
  create_folder(out_dir, "the run's outputs");

  if (options.first_frame > 0 && options.first_frame >= dataset.size()) {
    throw ConfigError::for_key("first_frame (--first-frame)",
                               fmt::format("is {} but {} has {} frames", options.first_frame,
                                           dataset.name(), dataset.size()));
  }
  const std::size_t begin = options.first_frame;
  // Masks precomputed for the stored RGB files reach the frames' (undistorted) grid.
  system.set_stored_mask_mapping(
      [&dataset](const cv::Mat& mask) { return dataset.undistort_mask(mask); });
  system.set_source_area(dataset.source_area());
  std::size_t end = dataset.size();
  if (options.max_frames > 0 && options.max_frames < end - begin) end = begin + options.max_frames;
  const std::size_t total = end - begin;

  // A map that cannot be loaded refuses the run before anything is written or removed.
  if (!options.load_map_path.empty()) system.load_map(options.load_map_path);
  // Ctrl-C while the models loaded: nothing ran, so the earlier run's outputs stay (review, stop
  // 25: they were removed and an empty run written in their place).
  if (stop != nullptr && stop->load()) throw Interrupted();
  // Every option is valid: from here on the run writes its outputs whatever happens.
  // The caller's own outputs first: if one cannot be written, the earlier run's outputs stay.
  if (options.on_start) options.on_start();
  remove_earlier_outputs(out_dir);
  RunOutcome outcome;
  std::exception_ptr error;
  Stopwatch wall;
  std::size_t done = 0;
  TimingStats input_timings;  // how long tracking waits for the next frame and its mask
  const double process_cpu_start_ms = process_cpu_ms();
  const double caller_cpu_start_ms = thread_cpu_ms();
  double caller_cpu_s = 0.0;  // this thread: tracking (deterministic mode: every stage inline)
  double input_done_s = 0.0;  // wall time when the last frame was processed (before shutdown)
  MaskEvaluator* const masks = system.config().dynamic.enabled ? options.mask_evaluator : nullptr;
  TimingStats latency;      // paced runs: from a frame's due time to the end of its tracking
  std::size_t dropped = 0;  // live runs: frames the pipeline was too busy to take
  std::vector<double> processed_stamps;  // not contiguous when frames were dropped
  try {
    PrefetchOptions prefetch;
    prefetch.pacer = pacer ? &*pacer : nullptr;  // a paced run loads each frame when it is due
    prefetch.drop_late = options.drop_late_frames;
    FramePrefetcher prefetcher(dataset, begin, end, prefetch);
    // CNN masks computed ahead of tracking in their own thread, in both modes (they depend only
    // on the frame). Destroyed before the prefetcher it reads from.
    // Live runs keep one frame between the CNN and tracking, as few as a frame buffer would.
    SegmentationStage segmentation([&] { return prefetcher.next(); },
                                   [&](const io::RgbdFrame& f) { return system.segment(f); },
                                   options.drop_late_frames ? 1 : 2,
                                   /*take_when_room=*/options.drop_late_frames);
    // Destroyed first: the segmentation worker must not wait for a frame's due time to stop.
    const struct CancelPacing {
      FramePacer* pacer;
      ~CancelPacing() {
        if (pacer != nullptr) pacer->cancel();
      }
    } cancel_pacing{pacer ? &*pacer : nullptr};
    while (true) {
      if (stop != nullptr && stop->load()) {
        outcome.interrupted = true;
        break;
      }
      const Stopwatch wait;
      std::optional<SegmentedFrame> segmented = segmentation.next();
      input_timings.record("input_wait", wait.elapsed_ms());
      if (!segmented) break;
      std::optional<io::RgbdFrame> frame = std::move(segmented->frame);
      const FrameOutcome result = system.process(*frame, std::move(segmented->cnn));
      if (pacer) latency.record("latency", pacer->latency_ms(frame->timestamp_s));
      if (masks != nullptr) masks->add(*frame, result.masks);
      processed_stamps.push_back(frame->timestamp_s);
      ++done;
      const bool go_on = !options.on_frame || options.on_frame(*frame, result);
      dropped = prefetcher.frames_dropped();
      if (progress) {
        progress(done + dropped, total,
                 fmt::format("{} kf, {}", system.statistics().keyframes_created,
                             tracking::to_string(result.tracking.state)));
      }
      if (!go_on) {
        outcome.interrupted = true;
        break;
      }
    }
    // Ctrl-C during a paced wait ends the input instead of the loop's own check.
    if (stop != nullptr && stop->load()) outcome.interrupted = true;
    dropped = prefetcher.frames_dropped();
    caller_cpu_s = (thread_cpu_ms() - caller_cpu_start_ms) / 1000.0;
    input_done_s = wall.elapsed_ms() / 1000.0;
    // Interrupted: a running global BA is aborted, the map and trajectory so far are written.
    system.finish(outcome.interrupted ? System::Finish::kInterrupted : System::Finish::kComplete);
  } catch (...) {
    error = std::current_exception();
    try {
      system.finish();
    } catch (...) {
      spdlog::error("a second error occurred while shutting down after the first");
    }
  }
  const double wall_s = wall.elapsed_ms() / 1000.0;
  if (input_done_s <= 0.0) input_done_s = wall_s;
  const double process_cpu_s = (process_cpu_ms() - process_cpu_start_ms) / 1000.0;

  // Outputs first, so that nothing computed is lost, then the error (if any) propagates. An
  // output that cannot be written does not stop the others or summary.json (which lists it under
  // output_errors); the run then fails with the first such error, after the frame error if any.
  std::vector<std::string> output_errors;
  const auto write_output = [&](const std::function<void()>& write) {
    try {
      write();
      return true;
    } catch (const Error& e) {
      spdlog::error("{}", e.what());
      output_errors.push_back(e.what());
      return false;
    }
  };
  const fs::path camera_path = out_dir / "CameraTrajectory.txt";
  const fs::path keyframe_path = out_dir / "KeyFrameTrajectory.txt";
  const bool camera_written = write_output([&] {
    io::write_tum_trajectory(camera_path.string(), system.camera_trajectory(),
                             "DDL-SLAM camera trajectory (T_w_c) of " + dataset.name());
  });
  const bool keyframes_written = write_output([&] {
    io::write_tum_trajectory(keyframe_path.string(), system.keyframe_trajectory(),
                             "DDL-SLAM keyframe trajectory (T_w_c) of " + dataset.name());
  });

  bool sparse_map_written = false;
  if (!options.save_map_path.empty()) {
    sparse_map_written = write_output([&] { system.save_map(options.save_map_path); });
  }
  for (const std::string& e : system.frame_output_errors()) {
    spdlog::error("{}", e);
    output_errors.push_back(e);
  }
  outcome.statistics = system.statistics();
  std::vector<std::string> map_files;
  write_output([&] {
    std::vector<std::string> errors;
    map_files = system.dense_mapper().write_outputs(out_dir.string(), errors);
    for (const std::string& e : errors) spdlog::error("{}", e);
    output_errors.insert(output_errors.end(), errors.begin(), errors.end());
  });
  nlohmann::json& summary = outcome.summary;
  summary["sequence"] = dataset.name();
  summary["frames_in_sequence"] = dataset.size();
  summary["frames_processed"] = done;
  summary["first_frame"] = options.first_frame;
  summary["max_frames"] = options.max_frames;
  summary["interrupted"] = outcome.interrupted;
  summary["playback_rate"] = pacer ? nlohmann::json(options.playback_rate) : nlohmann::json();
  summary["frames_dropped"] = dropped;
  summary["failed"] = error != nullptr;  // output errors: set below, with the evaluation's
  summary["wall_time_s"] = wall_s;
  summary["frames_per_second"] = wall_s > 0 ? static_cast<double>(done) / wall_s : 0.0;
  // The tracking rate: frames over the time until the last frame was tracked, before the
  // shutdown work (draining the dense stage's queue, the final octree rebuild, global BA).
  summary["tracking_frames_per_second"] =
      input_done_s > 0 ? static_cast<double>(done) / input_done_s : 0.0;
  summary["shutdown_s"] = wall_s - input_done_s;
  // CPU seconds, independent of other load on the machine (docs/dynamics.md, "Speed").
  summary["cpu_s"] = {{"process", process_cpu_s}, {"caller_thread", caller_cpu_s}};
  summary["statistics"] = statistics_to_json(outcome.statistics);
  nlohmann::json timing = timings_to_json(system.timings());
  timing.update(timings_to_json(system.dense_mapper().timings()));
  timing.update(timings_to_json(input_timings));
  timing.update(timings_to_json(latency));
  summary["timing_ms"] = timing;
  summary["dynamic"] = {{"enabled", system.config().dynamic.enabled},
                        {"segmenter", system.dynamic_front_end().segmenter_description()},
                        {"geometry_check", system.config().dynamic.use_geometry},
                        {"free_space_check", system.config().dynamic.free_space.enabled}};
  for (const std::string& f : map_files) {
    summary["outputs"]["map"].push_back(fs::path(f).filename().string());
  }
  if (masks != nullptr) {
    summary["masks"] = masks->to_json();
    if (write_output([&] { masks->write_frames_csv((out_dir / "mask_frames.csv").string()); })) {
      summary["outputs"]["mask_frames"] = "mask_frames.csv";
    }
  }
  if (camera_written) summary["outputs"]["camera_trajectory"] = camera_path.filename().string();
  // Not under "outputs", which lists the files of the output folder (removed by the next run in
  // it): the map may lie anywhere, and may be the one this run loaded.
  if (sparse_map_written) {
    summary["sparse_map"] =
        std::filesystem::absolute(options.save_map_path).lexically_normal().string();
  }
  if (keyframes_written) {
    summary["outputs"]["keyframe_trajectory"] = keyframe_path.filename().string();
  }

  const auto gt = dataset.groundtruth_path();
  if (options.evaluate && gt && error == nullptr && camera_written &&
      outcome.statistics.poses < 2) {
    summary["evaluation_error"] = fmt::format(
        "{} pose(s) estimated: the evaluation needs at least 2", outcome.statistics.poses);
    spdlog::warn("evaluation skipped: {}", summary["evaluation_error"].get<std::string>());
  }
  if (options.evaluate && gt && error == nullptr && camera_written &&
      outcome.statistics.poses >= 2) {
    // A malformed ground-truth file is bad input: the run ends with its error (exit code 2)
    // once summary.json is written. Failing to evaluate a run that is too short or too far from
    // the ground truth only skips the evaluation (below).
    std::optional<io::Trajectory> groundtruth;
    try {
      groundtruth = io::read_tum_trajectory(*gt);
    } catch (const InputError& e) {
      summary["evaluation_error"] = e.what();
      summary["failed"] = true;
      error = std::current_exception();
    }
    if (groundtruth) {
      try {
        eval::EvalResult result =
            eval::evaluate(*groundtruth, system.camera_trajectory(), {}, *gt, camera_path.string());
        // Tracked ratio against the frames that were processed (docs/evaluation.md): of the
        // processed frames inside the ground-truth span, those with an estimated pose. Until
        // 2026-11-26 it divided every estimated pose by those frames, so poses outside the span
        // could push it above 1 (found by review). Part of the result since stop 32, so that
        // eval.json and summary.json agree (eval.json said "unavailable" before).
        result.tracked =
            eval::compute_tracked(processed_stamps, result.groundtruth, result.estimate);
        result.inputs.frames_path = "(the frames this run processed)";
        // The report and plots are outputs: failing to write them fails the run (output_errors),
        // not the evaluation.
        const fs::path eval_dir = out_dir / "eval";
        write_output([&] {
          create_folder(eval_dir, "the evaluation");
          eval::write_json_report((eval_dir / "eval.json").string(), result);
          summary["outputs"]["evaluation"].push_back("eval/eval.json");
        });
        write_output([&] {
          for (const std::string& plot : eval::write_eval_plots(result, eval_dir.string())) {
            summary["outputs"]["evaluation"].push_back("eval/" +
                                                       fs::path(plot).filename().string());
          }
        });
        nlohmann::json ev = eval::to_json(result);
        // null when no processed frame lies inside the ground truth's span.
        ev["tracked_ratio"] = result.tracked->frames_in_gt_span > 0
                                  ? nlohmann::json(result.tracked->ratio)
                                  : nlohmann::json();
        summary["evaluation"] = ev;
        if (result.rpe_error.empty()) {
          spdlog::info("ATE RMSE {:.4f} m over {} poses, RPE {:.4f} m/s {:.3f} deg/s",
                       result.ate.stats_m.rmse, result.ate.errors_m.size(), result.rpe.trans_m.rmse,
                       result.rpe.rot_deg.rmse);
        } else {
          spdlog::info("ATE RMSE {:.4f} m over {} poses", result.ate.stats_m.rmse,
                       result.ate.errors_m.size());
          spdlog::warn("RPE unavailable: {}", result.rpe_error);
        }
      } catch (const Error& e) {
        spdlog::warn("evaluation skipped: {}", e.what());
        summary["evaluation_error"] = e.what();
      }
    }
  }
  if (!output_errors.empty()) {
    summary["output_errors"] = output_errors;
    summary["failed"] = true;
  }
  write_json(out_dir / "summary.json", summary);
  if (error) std::rethrow_exception(error);
  if (!output_errors.empty()) throw OutputError(output_errors.front());
  return outcome;
}

}  // namespace ddl::pipeline
