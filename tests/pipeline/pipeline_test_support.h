#pragma once
// Helpers of the whole-system tests: the shipped vocabulary, the plain SLAM core configuration,
// synthetic frames rendered in memory, pose errors.

#include <memory>
#include <string>

#include "ddl/core/se3.h"
#include "ddl/io/rgbd_frame.h"
#include "ddl/pipeline/system_config.h"
#include "ddl/synthetic/sequence.h"
#include "ddl/vocabulary/vocabulary.h"

namespace ddl::pipeline::testing {

/// vocab/ddl_orb_k10_l5.dvoc, loaded once; null when the file is absent (tests skip then).
std::shared_ptr<const vocabulary::Vocabulary> default_vocabulary();

/// The default settings, deterministic, without dynamic removal and dense mapping (the SLAM core
/// alone, as `ddl_slam run --no-dynamic --no-octomap --no-inpainting`).
SystemConfig core_config();

/// A synthetic preset with `frames` frames and procedural posters (no files needed).
synthetic::SequenceConfig preset_config(const std::string& preset, int frames);

/// Frame `index` of `source` as the pipeline consumes it (metric depth).
io::RgbdFrame to_rgbd(const synthetic::FrameData& data, const camera::PinholeCamera& camera);

struct PoseError {
  double translation_m = 0.0;
  double rotation_deg = 0.0;
};
/// Error of `estimate` against `truth` (both T_w_c in the same world frame).
PoseError pose_error(const SE3& estimate, const SE3& truth);

}  // namespace ddl::pipeline::testing
