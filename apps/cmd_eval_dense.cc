// `ddl_slam eval-dense`: a run's repaired keyframes and octree map against a synthetic sequence's
// ground truth (docs/dense.md).

#include <spdlog/spdlog.h>

#include <CLI/CLI.hpp>
#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

#include "cli_support.h"
#include "commands.h"
#include "ddl/config/dataset_config.h"
#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"
#include "ddl/eval/dense_eval.h"
#include "ddl/io/image_output.h"
#include "ddl/octomap/octree_map.h"

namespace ddl::app {
namespace {
namespace fs = std::filesystem;

struct EvalDenseArgs {
  eval::DenseEvalInputs inputs;
  eval::DenseEvalOptions options;
  std::string camera;
  std::string map_path;
  bool no_map = false;
  std::string json_path;
  std::string montage_path;
  std::string voxels_ply_path;
  bool align_positions = false;
  int montage_rows = 3;
  int montage_tile_width = 240;
};

int run_eval_dense(const EvalDenseArgs& args) {
  args.options.validate();  // before the octree is read: a bad option costs no wait
  eval::DenseEvalInputs inputs = args.inputs;
  inputs.camera = config::resolve_dataset_camera(inputs.sequence_dir, args.camera);
  if (!args.no_map) {
    std::string path = args.map_path;
    if (path.empty()) {
      for (const char* name : {"map.ot", "map.bt"}) {
        if (fs::exists(fs::path(inputs.run_dir) / name)) {
          path = (fs::path(inputs.run_dir) / name).string();
          break;
        }
      }
    }
    if (path.empty()) {
      spdlog::warn("{}: no map.ot or map.bt, map not evaluated", inputs.run_dir);
    } else {
      const octomap::OccupiedVoxels voxels = octomap::read_occupied_voxels(path);
      inputs.map = eval::MapVoxels{path, voxels.resolution_m, voxels.centres};
    }
  }
  eval::DenseEvalOptions options = args.options;
  options.align_with_orientations = !args.align_positions;
  const eval::DenseEvalResult result = eval::evaluate_dense(inputs, options);
  std::fputs(eval::format_dense_report(result).c_str(), stdout);
  std::fflush(stdout);
  if (!args.json_path.empty()) {
    write_file_atomically(
        args.json_path, "the JSON report",
        eval::to_json(result).dump(2, ' ', false, nlohmann::json::error_handler_t::replace) + '\n');
    spdlog::info("wrote {}", args.json_path);
  }
  if (!args.montage_path.empty()) {
    const cv::Mat montage =
        eval::inpainting_montage(result, args.montage_rows, args.montage_tile_width);
    if (montage.empty()) {
      spdlog::warn("no repaired keyframes: no montage written");
    } else {
      io::write_png(args.montage_path, montage, "the montage", 9);
      spdlog::info("wrote {}", args.montage_path);
    }
  }
  if (!args.voxels_ply_path.empty()) {
    if (!result.map) {
      spdlog::warn("no map evaluated: no classified voxels written");
    } else {
      eval::write_classified_voxels_ply(*result.map, args.voxels_ply_path);
      spdlog::info("wrote {}", args.voxels_ply_path);
    }
  }
  return kOk;
}

}  // namespace

void add_eval_dense_command(CLI::App& app, int& exit_code) {
  auto args = std::make_shared<EvalDenseArgs>();
  CLI::App* cmd = app.add_subcommand(
      "eval-dense",
      "Evaluate a run's dense outputs against a synthetic sequence's exact ground truth "
      "(docs/dense.md). Inpainting: the repaired keyframes of `run --save-inpainted` "
      "(<run>/inpainted/) against background/rgb and background/depth: fraction of the true "
      "dynamic pixels filled (of all, and of those an earlier keyframe saw), PSNR and median "
      "depth error over the filled pixels, beside the unfilled original frame. Map: the occupied "
      "voxels of <run>/map.ot, aligned to the ground truth as ATE aligns CameraTrajectory.txt, "
      "classified as near the true static geometry (background/depth at the true poses), ghost "
      "(near only dynamic geometry: depth/ under dynamic_mask/) or other.");
  cmd->add_option("--sequence", args->inputs.sequence_dir,
                  "Synthetic sequence folder (written by `ddl_slam synth`)")
      ->required();
  cmd->add_option("--run", args->inputs.run_dir, "Output folder of `ddl_slam run`")
      ->required()
      ->check(CLI::ExistingDirectory);
  cmd->add_option("--camera", args->camera,
                  "Camera of the sequence (as `run --camera`); default <sequence>/camera.yaml");
  cmd->add_option("--map", args->map_path,
                  "Octree file to evaluate; default <run>/map.ot, else <run>/map.bt");
  cmd->add_flag("--no-map", args->no_map, "Evaluate the inpainting only");
  cmd->add_option("--json", args->json_path, "Write the results as JSON to this file");
  cmd->add_option("--montage", args->montage_path,
                  "Write a PNG of repaired keyframes beside their originals and the true "
                  "background");
  cmd->add_option("--voxels-ply", args->voxels_ply_path,
                  "Write the map's voxel centres in the ground-truth frame as a PLY point cloud "
                  "coloured by class (near static green, ghost red, other blue)");
  cmd->add_option("--montage-rows", args->montage_rows, "Keyframes in the montage")
      ->check(CLI::Range(1, 12))
      ->capture_default_str();
  cmd->add_option("--montage-tile-width", args->montage_tile_width, "Tile width in pixels")
      ->check(CLI::Range(64, 640))
      ->capture_default_str();
  cmd->add_option("--previous-keyframes", args->options.previous_keyframes,
                  "A dynamic pixel is 'seen' when one of this many earlier keyframes saw its "
                  "background point")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--frame-stride", args->options.frame_stride,
                  "Reference geometry from every n-th frame of the run (and every keyframe)")
      ->check(CLI::NonNegativeNumber)
      ->capture_default_str();
  cmd->add_option("--pixel-stride", args->options.pixel_stride,
                  "Reference geometry from every n-th pixel in u and v")
      ->capture_default_str();
  cmd->add_flag("--align-positions", args->align_positions,
                "Align the map by positions only, as ATE aligns the trajectory (default: by whole "
                "poses, which stays determined when the camera hardly moves)");
  cmd->add_option("--radius-voxels", args->options.radius_voxels,
                  "A voxel is near geometry within this many voxel edges")
      ->capture_default_str();
  cmd->callback(
      [args, &exit_code] { exit_code = run_guarded([&] { return run_eval_dense(*args); }); });
}

}  // namespace ddl::app
