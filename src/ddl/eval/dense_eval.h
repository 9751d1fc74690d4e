#pragma once
// Evaluation of a finished run's dense outputs against a synthetic sequence's ground truth
// (`ddl_slam eval-dense`, docs/dense.md): the repaired keyframes written by `run
// --save-inpainted` (<run>/inpainted/<stamp>_{rgb,depth,mask,unfilled}.png) against the
// sequence's background/ images, and the occupied voxels of the run's octree against the static
// and dynamic geometry that the ground truth poses, background/depth, depth/ and dynamic_mask/
// give. The map is brought into the ground-truth frame by the ATE alignment of the run's
// CameraTrajectory.txt (eval::compute_ate, Horn).
// Thread-safety: functions of their inputs; reads files only.

#include <cstddef>
#include <nlohmann/json.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/eval/dense_metrics.h"

namespace ddl::eval {

/// The run's occupied voxels as the octree file holds them (map frame).
struct MapVoxels {
  std::string path;
  double resolution_m = 0.0;
  std::vector<Vec3d> centres;
};

struct DenseEvalInputs {
  std::string sequence_dir;      // synthetic sequence (groundtruth.txt, background/, ...)
  std::string run_dir;           // `ddl_slam run --out` folder
  camera::PinholeCamera camera;  // the sequence's camera as stored (distortion included)
  std::optional<MapVoxels> map;  // absent: no map evaluation
};

struct DenseEvalOptions {
  std::size_t previous_keyframes = 15;  // keyframes before each one that count for "seen"
  SeenOptions seen;                     // depth agreement for "seen"
  std::size_t frame_stride = 2;         // reference clouds: every n-th frame (+ every keyframe)
  int pixel_stride = 2;                 // reference clouds: every n-th pixel in u and v
  double radius_voxels = 2.0;           // "near" = within this many voxel edges
  double max_difference_s = 0.02;       // association of stamps with groundtruth.txt
  /// Map alignment: true = whole poses (align_poses, orientations included; well determined
  /// even for a camera that hardly moves), false = positions only, as ATE aligns.
  bool align_with_orientations = true;

  /// Throws ddl::ConfigError naming the option.
  void validate() const;
};

struct KeyframeEvaluation {
  std::size_t frame_index = 0;  // in the sequence
  std::string stem;             // <run>/inpainted/<stem>_*.png
  InpaintingFrameMetrics metrics;
};

struct MapEvaluation {
  std::string path;
  double resolution_m = 0.0;
  double radius_m = 0.0;
  VoxelClasses voxels;
  std::size_t reference_frames = 0;
  std::size_t static_points = 0;  // after merging to radius / 10
  std::size_t dynamic_points = 0;
  double alignment_rmse_m = 0.0;  // ATE RMSE of the alignment used
  std::size_t alignment_pairs = 0;
  std::vector<Vec3d> centres_gt;   // occupied voxel centres in the ground-truth frame
  std::vector<VoxelClass> labels;  // their classes, in the same order
};

/// Writes the classified voxel centres as an ASCII PLY point cloud in the ground-truth frame:
/// near static green, ghost red, other blue, whole or not at all. Throws OutputError naming the
/// file.
void write_classified_voxels_ply(const MapEvaluation& map, const std::string& path);

struct DenseEvalResult {
  DenseEvalInputs inputs;  // without the voxels
  DenseEvalOptions options;
  std::vector<KeyframeEvaluation> keyframes;  // empty: the run wrote no repaired keyframes
  InpaintingFrameMetrics total;
  std::optional<MapEvaluation> map;
};

/// Throws ddl::InputError naming the file for missing or malformed inputs (a repaired keyframe
/// whose stamp is not a frame of the sequence, a sequence without background/ or dynamic_mask/).
DenseEvalResult evaluate_dense(const DenseEvalInputs& inputs, const DenseEvalOptions& options = {});

/// Plain-text summary for a terminal.
std::string format_dense_report(const DenseEvalResult& result);
/// Totals, per-keyframe figures and the map classes; NaN as null.
nlohmann::json to_json(const DenseEvalResult& result);

/// Repaired keyframes beside their originals: `rows` keyframes (the one with the most dynamic
/// pixels in each of `rows` equal parts of the run), each row original (true dynamic outline in
/// red) | repaired (pixels left unfilled in magenta) | true background, tiles `tile_width` wide.
cv::Mat inpainting_montage(const DenseEvalResult& result, int rows = 3, int tile_width = 240);

}  // namespace ddl::eval
