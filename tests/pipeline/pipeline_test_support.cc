#include "pipeline_test_support.h"

#include <cmath>
#include <filesystem>

namespace ddl::pipeline::testing {

std::shared_ptr<const vocabulary::Vocabulary> default_vocabulary() {
  static const std::shared_ptr<const vocabulary::Vocabulary> vocabulary =
      []() -> std::shared_ptr<const vocabulary::Vocabulary> {
    const std::string path = std::string(DDL_SOURCE_DIR) + "/vocab/ddl_orb_k10_l5.dvoc";
    if (!std::filesystem::exists(path)) return nullptr;
    return std::make_shared<const vocabulary::Vocabulary>(vocabulary::Vocabulary::load(path));
  }();
  return vocabulary;
}

SystemConfig core_config() {
  SystemConfig config;
  config.mode = RunMode::kDeterministic;
  config.dynamic.enabled = false;
  config.dense.octomap_enabled = false;
  config.dense.inpainting_enabled = false;
  return config;
}

synthetic::SequenceConfig preset_config(const std::string& preset, int frames) {
  synthetic::SequenceConfig config = synthetic::find_preset(preset).config;
  config.frames = frames;
  return config;
}

io::RgbdFrame to_rgbd(const synthetic::FrameData& data, const camera::PinholeCamera& camera) {
  io::RgbdFrame frame;
  frame.index = data.index;
  frame.timestamp_s = data.rgb_stamp_s;
  frame.rgb = data.rgb;
  data.depth_raw.convertTo(frame.depth_m, CV_32FC1, 1.0 / camera.depth_factor);
  return frame;
}

PoseError pose_error(const SE3& estimate, const SE3& truth) {
  const SE3 delta = truth.inverse() * estimate;
  return {delta.translation().norm(), delta.rotation_vector().norm() * 180.0 / M_PI};
}

}  // namespace ddl::pipeline::testing
