// `ddl_slam run`: SLAM on one RGB-D sequence, with outputs and evaluation.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>

#include "cli_support.h"
#include "commands.h"
#include "ddl/config/camera_config.h"
#include "ddl/config/dataset_config.h"
#include "ddl/config/system_config.h"
#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"
#include "ddl/dynamics/mask_fusion.h"
#include "ddl/io/dataset_factory.h"
#include "ddl/pipeline/mask_evaluator.h"
#include "ddl/pipeline/sequence_runner.h"
#include "ddl/pipeline/system.h"
#include "ddl/viewer/viewer.h"
#include "ddl/vocabulary/vocabulary.h"
#include "run_command.h"

namespace ddl::app {
namespace {
namespace fs = std::filesystem;

// What the viewer shows of a processed frame.
viewer::ViewFrame to_view_frame(const io::RgbdFrame& frame, const pipeline::FrameOutcome& outcome,
                                std::size_t keyframes_created) {
  viewer::ViewFrame view;
  view.index = frame.index;
  view.rgb = frame.rgb;
  view.cnn = outcome.masks.cnn;
  // Both multi-view checks in one tint: the free-space check replaces the sparse one by default.
  view.geometry = dynamics::combine_masks(outcome.masks.geometry, outcome.masks.free_space);
  view.memory = outcome.masks.memory;
  view.keypoints.reserve(outcome.tracking.keypoints.size());
  for (const tracking::KeypointStatus& k : outcome.tracking.keypoints) {
    view.keypoints.push_back({cv::Point2f(k.u, k.v), k.matched});
  }
  view.state = std::string(tracking::to_string(outcome.tracking.state));
  view.T_w_c = outcome.tracking.T_w_c;
  view.keyframes = keyframes_created;
  view.map_reset = outcome.tracking.map_reset;
  return view;
}

}  // namespace

std::string resolve_vocabulary(const std::string& flag) {
  if (!flag.empty()) return flag;
  if (const char* env = std::getenv("DDL_VOCABULARY"); env != nullptr && *env != '\0') return env;
  return config::default_vocabulary_path();
}

std::shared_ptr<const vocabulary::Vocabulary> load_vocabulary(const std::string& path) {
  Stopwatch load_watch;
  auto vocabulary =
      std::make_shared<const vocabulary::Vocabulary>(vocabulary::Vocabulary::load(path));
  spdlog::info("vocabulary {}: {} words, loaded in {:.0f} ms", path, vocabulary->word_count(),
               load_watch.elapsed_ms());
  return vocabulary;
}

pipeline::SystemConfig make_system_config(const RunArgs& args) {
  const std::string shared_dir = resolve_shared_dir(args.shared_dir);

  pipeline::SystemConfig config = args.config_path.empty()
                                      ? pipeline::SystemConfig{}
                                      : config::load_system_config(args.config_path);
  if (!args.mode.empty()) config.mode = config::parse_run_mode(args.mode, "--mode");
  if (args.no_dynamic) config.dynamic.enabled = false;
  if (args.no_loop) config.loop.enabled = false;
  if (args.no_octomap) config.dense.octomap_enabled = false;
  if (args.no_inpainting) config.dense.inpainting_enabled = false;
  if (args.save_masks) config.save_masks = true;
  if (args.localization_only) config.tracking.localization_only = true;
  if (config.tracking.localization_only && args.load_map.empty()) {
    throw ConfigError::for_key("--localization-only (tracking.localization_only)",
                               "needs a map to track against: --load-map FILE");
  }
  if (args.save_inpainted) {
    config.dense.save_inpainted_dir = (fs::path(args.output_dir) / "inpainted").string();
  }
  if (!args.segmentation.empty()) {
    config.dynamic.segmentation.backend =
        config::parse_segmentation_backend(args.segmentation, "--segmentation");
  }
  config.shared_dir = shared_dir;
  config.output_dir = args.output_dir;
  config.validate();
  return config;
}

RunResult run_sequence_command(const RunArgs& args,
                               std::shared_ptr<const vocabulary::Vocabulary> vocabulary,
                               const std::atomic<bool>* stop) {
  const pipeline::SystemConfig config = make_system_config(args);
  // The viewer's settings are checked before anything is loaded.
  std::optional<viewer::ViewerConfig> view_config;
  if (args.viewer || !args.save_viewer_dir.empty() || !args.save_viewer_video.empty()) {
    view_config.emplace();
    view_config->window = args.viewer;
    view_config->output_dir = args.save_viewer_dir;
    view_config->video_path = args.save_viewer_video;
    view_config->every_n_frames = args.viewer_every;
    try {
      view_config->validate();
    } catch (const ConfigError& e) {
      throw ConfigError(fmt::format("--viewer-every / --save-viewer: {}", e.what()));
    }
    if (args.viewer) {
      if (const std::optional<std::string> problem = viewer::probe_window_system()) {
        throw Error(*problem);
      }
    }
  }

  io::DatasetOptions dataset_options;
  dataset_options.kind = io::parse_dataset_kind(args.dataset_kind, "--dataset-kind");
  dataset_options.sequence.association =
      io::parse_association_source(args.associations, "--associations");
  dataset_options.camera =
      config::resolve_dataset_camera(args.sequence, args.camera, dataset_options.kind);
  // A run that does not evaluate does not depend on groundtruth.txt.
  dataset_options.sequence.check_groundtruth_on_open = !args.no_eval;
  // Only upright segmentation reads the accelerometer (docs/dynamics.md).
  dataset_options.sequence.read_accelerometer = config.dynamic.enabled &&
                                                config.dynamic.use_segmentation &&
                                                config.dynamic.segmentation.upright;
  const std::unique_ptr<io::DatasetReader> dataset =
      io::open_dataset(args.sequence, dataset_options);
  spdlog::info("{}: {} frames, camera {}", dataset->name(), dataset->size(),
               dataset->camera().name);

  if (!vocabulary) vocabulary = load_vocabulary(resolve_vocabulary(args.vocabulary_path));

  create_folder(args.output_dir, "the run's outputs");
  pipeline::System system(config, dataset->camera(), vocabulary);

  pipeline::RunOptions run_options;
  run_options.output_dir = args.output_dir;
  run_options.first_frame = args.first_frame;
  run_options.max_frames = args.max_frames;
  run_options.playback_rate = args.playback_rate;
  run_options.drop_late_frames = args.drop_late_frames;
  run_options.evaluate = !args.no_eval;
  run_options.load_map_path = args.load_map;
  run_options.save_map_path = args.save_map;
  // Written once the run has found its options valid: a run refused at its start (a bad
  // --first-frame, a missing model) leaves an earlier run's folder consistent.
  run_options.on_start = [&] {
    write_file_atomically(fs::path(args.output_dir) / "config.yaml", "the effective configuration",
                          config::system_config_to_yaml(config));
    // The calibration of the sequence's stored images, distortion included: `--camera` with this
    // file runs the sequence again as this run did (the frames are undistorted to the same
    // intrinsics). Until stop 24 it was the undistorted camera, which skipped the undistortion.
    write_file_atomically(fs::path(args.output_dir) / "camera.yaml",
                          "the camera of the sequence's images",
                          config::camera_to_yaml(*dataset_options.camera));
  };
  // Ground-truth dynamic masks (sequences written by `ddl_slam synth`): mask quality metrics.
  std::unique_ptr<pipeline::MaskEvaluator> mask_evaluator;
  if (config.dynamic.enabled && !args.no_eval) {
    mask_evaluator = pipeline::MaskEvaluator::open(args.sequence, *dataset_options.camera);
  }
  run_options.mask_evaluator = mask_evaluator.get();
  std::unique_ptr<viewer::Viewer> view;
  if (view_config) {
    // The video plays at the sequence's rate, whichever frames are drawn.
    // OpenCV's Motion-JPEG writer takes 1 to 1000 frames per second: a sparser stride plays faster.
    const double fps = dataset->camera().fps / view_config->every_n_frames;
    view_config->video_fps = std::clamp(fps, 1.0, 1000.0);
    if (!view_config->video_path.empty() && view_config->video_fps != fps) {
      spdlog::warn("viewer video: {:.3g} views per second of the sequence, written at {:g} fps",
                   fps, view_config->video_fps);
    }
    view = std::make_unique<viewer::Viewer>(*view_config, system.map());
    run_options.on_frame = [&](const io::RgbdFrame& frame, const pipeline::FrameOutcome& result) {
      view->show(to_view_frame(frame, result, system.statistics().keyframes_created));
      if (view->stop_requested()) spdlog::info("viewer: stop requested in the window");
      return !view->stop_requested();
    };
  }
  Progress progress("run " + dataset->name(),
                    std::min(dataset->size() - std::min(dataset->size(), args.first_frame),
                             args.max_frames == 0 ? dataset->size() : args.max_frames));
  const pipeline::RunOutcome outcome = pipeline::run_sequence(
      *dataset, system, run_options, stop,
      [&](std::size_t done, std::size_t, const std::string& note) { progress.update(done, note); });
  if (outcome.interrupted) {
    progress.finish_early("interrupted");
  } else {
    progress.finish();
  }
  if (view) {
    view->finish();
    spdlog::info("viewer: {} views drawn{}{}", view->frames_drawn(),
                 args.save_viewer_dir.empty() ? "" : " to " + args.save_viewer_dir,
                 args.save_viewer_video.empty() ? "" : " and " + args.save_viewer_video);
  }
  return {outcome.interrupted, outcome.summary};
}

namespace {

int run(const RunArgs& args) {
  const auto& stop = install_stop_handler();
  const RunResult outcome = run_sequence_command(args, nullptr, &stop);
  const nlohmann::json& s = outcome.summary["statistics"];

  std::printf(
      "frames %zu, tracked %zu, lost %zu, keyframes %zu, map points %zu, loops %zu, "
      "relocalizations %zu\n",
      s["frames"].get<std::size_t>(), s["frames_tracked"].get<std::size_t>(),
      s["frames_lost"].get<std::size_t>(), s["keyframes"].get<std::size_t>(),
      s["map_points"].get<std::size_t>(), s["loops_closed"].get<std::size_t>(),
      s["relocalizations"].get<std::size_t>());
  // A statistic, or NaN where it is null (undefined, or an RPE that is unavailable).
  const auto value = [](const nlohmann::json& v) { return v.is_number() ? v.get<double>() : NAN; };
  if (outcome.summary.contains("evaluation")) {
    const auto& ev = outcome.summary["evaluation"];
    // The RPE may be unavailable (a run shorter than its delta): the ATE still is.
    const double rpe_t = value(ev["rpe"]["trans_rmse_m_per_s"]);
    const std::string rpe = std::isfinite(rpe_t)
                                ? fmt::format("RPE {:.4f} m/s {:.3f} deg/s", rpe_t,
                                              value(ev["rpe"]["rot_rmse_deg_per_s"]))
                                : std::string("RPE unavailable (shorter than its delta)");
    std::printf("ATE RMSE %.4f m, %s, tracked ratio %.3f\n", value(ev["ate"]["rmse_m"]),
                rpe.c_str(), value(ev["tracked_ratio"]));
  }
  if (outcome.summary.contains("masks")) {
    const auto& m = outcome.summary["masks"];
    // "-" where a score is undefined (no dynamic pixel in the truth, or none marked).
    const auto scores = [&value](const nlohmann::json& kind) {
      std::string out;
      for (const char* key : {"mean_iou", "precision", "recall"}) {
        const double v = value(kind[key]);
        out += (out.empty() ? "" : "/") + (std::isfinite(v) ? fmt::format("{:.3f}", v) : "-");
      }
      return out;
    };
    std::printf(
        "dynamic masks (IoU / precision / recall): cnn %s, geometry %s, free space %s, combined "
        "%s\n",
        scores(m["cnn"]).c_str(), scores(m["geometry"]).c_str(), scores(m["free_space"]).c_str(),
        scores(m["combined"]).c_str());
  }
  std::printf("outputs in %s\n", args.output_dir.c_str());
  return outcome.interrupted ? kInterrupted : kOk;
}

}  // namespace

void add_run_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<RunArgs>();
  CLI::App* cmd = app.add_subcommand(
      "run",
      "Run DDL-SLAM on an RGB-D sequence in the TUM layout (TUM RGB-D, Bonn RGB-D Dynamic, or "
      "one written by `ddl_slam synth`). Writes CameraTrajectory.txt, KeyFrameTrajectory.txt "
      "(TUM format), summary.json, config.yaml, the octree map (map.ot/map.bt/map.ply + PNG "
      "renderings) and, when the sequence has groundtruth.txt, eval/ with ATE/RPE and plots; "
      "with ground-truth masks (dynamic_mask.txt, from `ddl_slam synth`) the mask quality goes "
      "into summary.json. "
      "Ctrl-C stops cleanly and saves what was computed.");
  cmd->add_option("sequence", args->sequence, "Sequence folder (rgb.txt, depth.txt, ...)")
      ->required();
  cmd->add_option("--camera", args->camera,
                  "Camera: tum1, tum2, tum3, bonn, synthetic or a YAML file; default: from the "
                  "folder name (freiburg1/2/3, rgbd_bonn_*) or <sequence>/camera.yaml");
  cmd->add_option("--config", args->config_path,
                  "System settings (YAML; every key in docs/configuration.md). Unknown keys are "
                  "errors");
  cmd->add_option("--out", args->output_dir, "Output folder")->capture_default_str();
  cmd->add_option("--vocabulary", args->vocabulary_path,
                  "ORB vocabulary file; default $DDL_VOCABULARY or the one shipped in vocab/");
  cmd->add_option("--mode", args->mode,
                  "deterministic (all stages inline, reproducible) or threaded (stages in their "
                  "own threads, for speed); default from the settings (deterministic)")
      ->check(CLI::IsMember({"deterministic", "threaded"}));
  cmd->add_option("--dataset-kind", args->dataset_kind, "auto, tum or bonn")
      ->check(CLI::IsMember({"auto", "tum", "bonn"}))
      ->capture_default_str();
  cmd->add_option("--associations", args->associations,
                  "auto (associations.txt if present, else associate rgb.txt/depth.txt as TUM's "
                  "associate.py), file, or timestamps")
      ->check(CLI::IsMember({"auto", "file", "timestamps"}))
      ->capture_default_str();
  cmd->add_option("--segmentation", args->segmentation,
                  "Segmentation backend: onnx (default model in the shared folder), folder, none");
  cmd->add_option("--shared-dir", args->shared_dir,
                  "Shared data folder (models); default $DDL_SHARED_DIR or ../shared");
  cmd->add_option("--first-frame", args->first_frame, "Skip the frames before this index")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--max-frames", args->max_frames, "Process at most this many frames (0 = all)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_option("--playback-rate", args->playback_rate,
                  "Feed the frames at RATE times the pace of their timestamps, as a live camera "
                  "delivers them (1 = real time; none is dropped without --drop-late-frames; "
                  "summary.json's timing_ms.latency tells how far behind they were handled); 0 "
                  "(default): as fast as they are taken")
      ->check(CLI::Range(0.0, 1000.0));
  cmd->add_flag("--drop-late-frames", args->drop_late_frames,
                "With --playback-rate: keep only the newest frame, as a live camera with a "
                "one-frame buffer does: a frame a newer one arrived before the pipeline took is "
                "dropped (latency stays bounded; which frames are "
                "dropped depends on timing, so runs differ; summary.json frames_dropped)");
  cmd->add_flag("--no-dynamic", args->no_dynamic,
                "Plain SLAM core without dynamic-content removal (the paper's ORB-SLAM2 column)");
  cmd->add_flag("--no-loop", args->no_loop, "Disable loop closing");
  cmd->add_flag("--no-octomap", args->no_octomap, "Do not build the octree map");
  cmd->add_flag("--no-inpainting", args->no_inpainting, "Do not repair keyframes");
  cmd->add_flag("--save-masks", args->save_masks,
                "Write the dynamic masks to <out>/masks/ (combined; the CNN, geometry, memory and "
                "free-space parts in subfolders)");
  cmd->add_flag("--save-inpainted", args->save_inpainted,
                "Write repaired keyframes to <out>/inpainted/");
  cmd->add_option("--save-map", args->save_map,
                  "Write the sparse map (keyframes, map points, the octree's scans) to FILE at "
                  "the end of the run, also when it is interrupted (docs/map-files.md)");
  cmd->add_option("--load-map", args->load_map,
                  "Start in the sparse map FILE written by --save-map with the same camera and "
                  "vocabulary: the first frames relocalize in it, and the run extends it "
                  "(docs/map-files.md)");
  cmd->add_flag("--localization-only", args->localization_only,
                "With --load-map: track against the loaded map without changing it (no keyframe "
                "is created; ORB-SLAM2's localization mode; tracking.localization_only)");
  cmd->add_flag("--no-eval", args->no_eval, "Skip the evaluation against groundtruth.txt");
  cmd->add_flag("--viewer", args->viewer,
                "Show the viewer window: the frame with its dynamic masks and keypoints beside "
                "the map (needs a display; 'q' or Esc stops the run cleanly). See docs/viewer.md");
  cmd->add_option("--save-viewer", args->save_viewer_dir,
                  "Write the viewer's images to DIR (frame_NNNNNN.png; every drawn frame, so a "
                  "deterministic run gives the same images)");
  cmd->add_option("--save-viewer-video", args->save_viewer_video,
                  "Write the viewer's views as a Motion-JPEG AVI video FILE, at the sequence's "
                  "frame rate divided by --viewer-every");
  cmd->add_option("--viewer-every", args->viewer_every,
                  "Draw only the frames whose index is a multiple of N")
      ->check(CLI::PositiveNumber)
      ->capture_default_str();
  cmd->callback([args, &exit_code] { exit_code = run_guarded([&] { return run(*args); }); });
}

}  // namespace ddl::app
