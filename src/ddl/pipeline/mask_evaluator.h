#pragma once
// Evaluates the dynamic masks of a run against a sequence's ground-truth masks, frame by frame:
// the hook that run_sequence() feeds (RunOptions::mask_evaluator). Ground truth is the layout that
// `ddl_slam synth` writes (docs/synthetic.md): <sequence>/dynamic_mask.txt listing
// dynamic_mask/<rgb stamp>.png, 255 = dynamic entity visible. The CNN, geometry and combined masks
// are scored separately (eval/mask_metrics.h); docs/evaluation.md documents the "masks" object of
// summary.json.
//
// The moved box of the sitting/desk presets: dynamic_mask marks it from the moment it starts
// moving, together with the people, and no per-entity mask is written. Its pixels are separated
// with meta.json (the box's size, per-frame centre, yaw path) and groundtruth.txt (the camera
// pose): the convex hull of its eight projected corners, grown by a few pixels, intersected with
// the ground-truth mask (MovedObjectRegion).
//
// Void: a composite whose real frames show an a-priori dynamic class that is not part of the
// dynamic truth (fr1_rpy's seated man) lists void_mask/<rgb stamp>.png in void_mask.txt, 255 =
// not scored. Those pixels count neither as true nor as false in any score (PASCAL VOC's void).
// Recall on those pixels measures what the geometry check adds for a non-a-priori-dynamic object.
// Thread-safety: not synchronised; one thread feeds it.

#include <cstdint>
#include <memory>
#include <nlohmann/json.hpp>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <utility>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/eval/mask_metrics.h"
#include "ddl/io/rgbd_frame.h"
#include "ddl/io/trajectory_io.h"
#include "ddl/pipeline/dynamic_front_end.h"

namespace ddl::pipeline {

/// The image region of the synthetic presets' moved box, from meta.json and groundtruth.txt.
class MovedObjectRegion {
 public:
  /// nullopt when the sequence has no meta.json, no "scene.object" in it, or no groundtruth.txt.
  /// Throws ddl::InputError naming the file when meta.json is malformed.
  static std::optional<MovedObjectRegion> load(const std::string& sequence_dir,
                                               const camera::PinholeCamera& camera,
                                               int grow_px = 3);

  /// CV_8UC1 255 where the box may be visible in the frame at `stamp_s` (convex hull of its
  /// projected corners grown by grow_px); empty when the box is not dynamic at that frame, a
  /// corner is behind the camera, or the frame or its pose is unknown.
  cv::Mat region(double stamp_s) const;
  int grow_px() const { return grow_px_; }

 private:
  struct FrameState {
    double stamp_s = 0.0;
    bool dynamic = false;
    Vec3d centre_w = Vec3d::Zero();
  };
  camera::PinholeCamera camera_;
  int grow_px_ = 3;
  Vec3d size_m_ = Vec3d::Zero();
  double yaw_from_ = 0.0, yaw_to_ = 0.0;
  Vec3d from_w_ = Vec3d::Zero(), to_w_ = Vec3d::Zero();
  std::vector<FrameState> frames_;  // by stamp
  io::Trajectory groundtruth_;
};

class MaskEvaluator {
 public:
  /// nullptr when `sequence_dir` has no dynamic_mask.txt. `stored_camera` is the calibration of
  /// the stored images: with distortion, the ground-truth masks are undistorted (nearest
  /// neighbour) like the frames. Throws ddl::InputError naming the list when it is malformed.
  static std::unique_ptr<MaskEvaluator> open(const std::string& sequence_dir,
                                             const camera::PinholeCamera& stored_camera);

  /// Scores the frame's masks; a frame without a ground-truth mask (stamp not in the list) is
  /// counted in frames_without_truth. Throws ddl::InputError naming an unreadable mask file.
  void add(const io::RgbdFrame& frame, const DynamicMasks& masks);

  /// {truth, frames_without_truth, void, cnn, geometry, free_space, combined[, moved_object]}, see
  /// docs/evaluation.md.
  nlohmann::json to_json() const;

  eval::MaskSummary summary(const std::string& source) const;

  /// Writes the per-frame counts (mask_frames.csv, docs/evaluation.md): a header, then one row per
  /// scored frame in the order added: stamp, truth_px, and tp,fp,fn per source (cnn, geometry,
  /// free_space, combined). Throws ddl::OutputError naming the file when it cannot be written.
  void write_frames_csv(const std::string& path) const;

 private:
  MaskEvaluator(std::string sequence_dir, const camera::PinholeCamera& stored_camera);
  /// The mask `file` (relative to the sequence), undistorted like the frames.
  cv::Mat read_mask(const std::string& file) const;

  std::string sequence_dir_;
  std::vector<std::pair<double, std::string>> truth_;  // (stamp, relative path), by stamp
  std::vector<std::pair<double, std::string>> void_;   // void_mask.txt, the same; may be empty
  std::uint64_t void_pixels_ = 0;                      // void pixels over the scored frames
  camera::Undistorter undistorter_;
  std::optional<MovedObjectRegion> moved_object_;
  std::size_t frames_without_truth_ = 0;
  eval::MaskAccumulator cnn_, geometry_, free_space_, combined_;
  eval::MaskCounts object_cnn_, object_geometry_, object_free_space_, object_combined_;
  std::size_t object_frames_ = 0;
  struct FrameCounts {
    double stamp_s = 0.0;
    eval::MaskCounts cnn, geometry, free_space, combined;
  };
  std::vector<FrameCounts> frames_;  // per scored frame, in the order added
};

}  // namespace ddl::pipeline
