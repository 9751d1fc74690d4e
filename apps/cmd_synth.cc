// `ddl_slam synth`: write dynamic RGB-D benchmark sequences with exact ground truth in the TUM
// layout (synthetic rooms with people, and composites of real TUM frames with real people).

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <string>
#include <vector>

#include "cli_support.h"
#include "commands.h"
#include "ddl/config/dataset_config.h"
#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"
#include "ddl/core/timing.h"
#include "ddl/io/image_output.h"
#include "ddl/synthetic/preview.h"
#include "ddl/synthetic/sequence.h"

namespace ddl::app {
namespace {

namespace fs = std::filesystem;

struct SynthArgs {
  bool list = false;
  std::string preset;
  std::string out;
  std::string suite;
  int frames = 0;
  long long seed = -1;
  std::string people_dir;
  std::string background;
  std::string shared_dir;
  bool procedural = false;
  std::string preview;
  int preview_frame = -1;
  bool preview_only = false;
  int png_compression = 1;
};

synthetic::SequenceConfig config_for(const synthetic::Preset& preset, const SynthArgs& args) {
  synthetic::SequenceConfig config = preset.config;
  const std::string shared = resolve_shared_dir(args.shared_dir);
  if (args.frames > 0) config.frames = args.frames;
  if (args.seed >= 0) config.seed = static_cast<std::uint64_t>(args.seed);
  if (!args.procedural) {
    config.people_dir =
        args.people_dir.empty() ? (fs::path(shared) / "data/people/ccp").string() : args.people_dir;
    config.poster_images = synthetic::default_poster_images();
  }
  if (!args.background.empty()) {
    config.background_dir = args.background;
    // The background's own camera (freiburg1/2/3 from the folder name, or its camera.yaml):
    // people are drawn, and camera.yaml written, with it. It was always fr1's until 2026-11-26
    // (found by review): on fr3 frames the people sat 4-8 px off the real scene.
    config.background_camera = config::resolve_dataset_camera(args.background, "");
    // A preset's void boxes (world frame) describe its own background sequence only.
    const fs::path own = fs::path(preset.background_in_shared).filename();
    fs::path given = fs::path(args.background).lexically_normal();
    if (given.filename().empty()) given = given.parent_path();  // a trailing '/'
    if (!config.void_boxes_w.empty() && given.filename() != own) {
      spdlog::warn("synth: the void boxes of {} describe {}, not {}: no void masks", preset.name,
                   own.string(), args.background);
      config.void_boxes_w.clear();
    }
  } else if (!preset.background_in_shared.empty()) {
    config.background_dir = (fs::path(shared) / preset.background_in_shared).string();
  }
  if (!args.people_dir.empty() && !fs::is_directory(fs::path(args.people_dir) / "images")) {
    throw InputError::at(args.people_dir, "--people-dir: no images/ folder of person photos");
  }
  if (config.people != synthetic::PeopleScenario::kNone && !config.people_dir.empty() &&
      !fs::is_directory(fs::path(config.people_dir) / "images")) {
    spdlog::warn("synth: no person photos in {} - using procedural silhouettes", config.people_dir);
  }
  return config;
}

void write_preview(const synthetic::SequenceSource& source, const SynthArgs& args,
                   const std::string& path) {
  const std::size_t n = source.frame_count();
  std::size_t index =
      args.preview_frame >= 0 ? static_cast<std::size_t>(args.preview_frame) : n / 2;
  if (index >= n) {
    throw ConfigError::for_key("--preview-frame",
                               fmt::format("frame {} does not exist ({} frames)", index, n));
  }
  const auto frame = source.render_frame(index);
  cv::Mat picture = synthetic::make_preview(frame, source.camera().depth_factor);
  // 32 levels per channel: the documentation pictures stay well under 300 KB as PNG.
  picture &= cv::Scalar(0xf8, 0xf8, 0xf8);
  io::write_png(path, picture, "the preview image", 9);
  spdlog::info("synth: preview of frame {} written to {}", index, path);
}

void generate(const synthetic::Preset& preset, const SynthArgs& args, const std::string& out_dir,
              const std::atomic<bool>& stop) {
  const synthetic::SequenceConfig config = config_for(preset, args);
  Stopwatch setup;
  const auto source = synthetic::make_sequence_source(config);
  spdlog::info("synth: {}: {} frames, scene ready in {:.1f} s", preset.name, source->frame_count(),
               setup.elapsed_ms() / 1000.0);
  if (!args.preview.empty()) write_preview(*source, args, args.preview);
  if (args.preview_only) return;
  Progress progress(preset.name, source->frame_count());
  synthetic::WriteOptions options;
  options.stop = &stop;
  options.png_compression = args.png_compression;
  options.progress = [&](std::size_t done, std::size_t) { progress.update(done); };
  Stopwatch timer;
  synthetic::write_sequence(*source, out_dir, options);
  progress.finish();
  const double seconds = timer.elapsed_ms() / 1000.0;
  std::printf(
      "%s: %zu frames written to %s in %.1f s (%.1f ms/frame)\n", preset.name.c_str(),
      source->frame_count(), out_dir.c_str(), seconds,
      1000.0 * seconds / static_cast<double>(std::max<std::size_t>(1, source->frame_count())));
}

int run_synth(const SynthArgs& args) {
  if (args.list) {
    for (const auto& p : synthetic::presets()) {
      const int frames = p.config.frames;
      std::printf("%-26s %5s  %s\n", p.name.c_str(),
                  frames > 0 ? std::to_string(frames).c_str() : "all", p.description.c_str());
    }
    return kOk;
  }
  const auto& stop = install_stop_handler();
  if (!args.suite.empty()) {
    for (const auto& preset : synthetic::presets()) {
      if (!preset.background_in_shared.empty() && args.background.empty()) {
        const fs::path bg =
            fs::path(resolve_shared_dir(args.shared_dir)) / preset.background_in_shared;
        if (!fs::is_directory(bg)) {
          spdlog::warn("synth: skipping {}: background sequence {} not found", preset.name,
                       bg.string());
          continue;
        }
      }
      generate(preset, args, (fs::path(args.suite) / preset.name).string(), stop);
    }
    return kOk;
  }
  if (args.preset.empty()) {
    throw ConfigError::for_key("--preset", "give --preset NAME (see --list) or --suite DIR");
  }
  if (args.out.empty() && !args.preview_only) {
    throw ConfigError::for_key("--out", "give the output folder of the sequence");
  }
  generate(synthetic::find_preset(args.preset), args, args.out, stop);
  return kOk;
}

}  // namespace

void add_synth_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<SynthArgs>();
  CLI::App* cmd = app.add_subcommand(
      "synth",
      "Write dynamic RGB-D benchmark sequences with exact ground truth, in the TUM layout:\n"
      "rgb/ depth/ rgb.txt depth.txt associations.txt groundtruth.txt, plus dynamic_mask/,\n"
      "background/rgb/ and background/depth/ (the frame without dynamic objects), camera.yaml\n"
      "and meta.json. Synthetic rooms are rendered with people (photos from\n"
      "<shared>/data/people/ccp, else silhouettes) along TUM-like camera motions; the composite\n"
      "preset renders real people into a real TUM sequence and marks the real person seated\n"
      "in it void (void_mask/: not scored). Same seed, same bytes.\n"
      "Examples:\n"
      "  ddl_slam synth --list\n"
      "  ddl_slam synth --preset syn_walking_xyz --out out/syn_walking_xyz\n"
      "  ddl_slam synth --preset syn_static_loop --out /tmp/loop --frames 300 --seed 7\n"
      "  ddl_slam synth --suite out/synthetic\n"
      "See docs/synthetic.md.");
  cmd->add_flag("--list", args->list, "List the presets and exit");
  cmd->add_option("--preset", args->preset, "Preset to generate (see --list)");
  cmd->add_option("--out", args->out, "Output folder of the sequence (with --preset)");
  cmd->add_option("--suite", args->suite,
                  "Write every preset into DIR/<preset> (the composite is skipped with a warning "
                  "when its background sequence is missing)");
  cmd->add_option("--frames", args->frames,
                  "Number of frames (default: the preset's; composite: the first N)")
      ->check(CLI::Range(1, 100000));
  cmd->add_option("--seed", args->seed, "Random seed (default: the preset's)")
      ->check(CLI::Range(0LL, 9007199254740991LL));
  cmd->add_option("--people-dir", args->people_dir,
                  "Photos of people with masks: DIR/images/NNNN.jpg + DIR/masks/NNNN.png "
                  "(default: <shared>/data/people/ccp; missing: procedural silhouettes)");
  cmd->add_option("--background", args->background,
                  "TUM sequence folder to composite people into (with groundtruth.txt); makes "
                  "any preset a composite");
  cmd->add_option("--shared-dir", args->shared_dir,
                  "Shared data folder (default: $DDL_SHARED_DIR, else ../shared)");
  cmd->add_flag("--procedural", args->procedural,
                "Use no photos at all: procedural posters and silhouettes (as on a fresh machine)");
  CLI::Option* preview =
      cmd->add_option("--preview", args->preview,
                      "Also write a side-by-side picture (rgb | depth | mask | background) of one "
                      "frame to this PNG");
  cmd->add_option("--preview-frame", args->preview_frame,
                  "Frame of the preview (default: the middle one)")
      ->check(CLI::NonNegativeNumber);
  cmd->add_flag("--preview-only", args->preview_only, "Write only the preview, no sequence")
      ->needs(preview);
  cmd->add_option("--png-compression", args->png_compression, "zlib level of the PNGs, 0-9")
      ->check(CLI::Range(0, 9))
      ->capture_default_str();
  cmd->callback([args, &exit_code] { exit_code = run_guarded([&] { return run_synth(*args); }); });
}

}  // namespace ddl::app
