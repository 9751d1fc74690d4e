// Sequence configuration, its validation and the preset suite.

#include <fmt/format.h>

#include <cmath>

#include "ddl/core/error.h"
#include "ddl/synthetic/sequence.h"

namespace ddl::synthetic {

std::string to_string(PeopleScenario scenario) {
  switch (scenario) {
    case PeopleScenario::kNone:
      return "none";
    case PeopleScenario::kWalking:
      return "walking";
    case PeopleScenario::kSitting:
      return "sitting";
    case PeopleScenario::kDeskPerson:
      return "desk_person";
  }
  return "?";
}

PeopleScenario parse_people_scenario(const std::string& text, const std::string& key) {
  for (auto s : {PeopleScenario::kNone, PeopleScenario::kWalking, PeopleScenario::kSitting,
                 PeopleScenario::kDeskPerson}) {
    if (to_string(s) == text) return s;
  }
  throw ConfigError::for_key(
      key, fmt::format("unknown people scenario '{}' (expected none, walking, sitting, "
                       "desk_person)",
                       text));
}

std::vector<std::string> default_poster_images() {
  const std::string dir = "/usr/share/doc/opencv-doc/examples/data/";
  return {dir + "board.jpg", dir + "fruits.jpg", dir + "starry_night.jpg", dir + "graf1.png"};
}

camera::PinholeCamera tum3_camera() {
  camera::PinholeCamera c;
  c.name = "tum3_synthetic";
  c.width = 640;
  c.height = 480;
  c.fx = 535.4;
  c.fy = 539.2;
  c.cx = 320.1;
  c.cy = 247.6;
  c.distortion = {0, 0, 0, 0, 0};
  c.depth_factor = 5000.0;
  c.fps = 30.0;
  return c;
}

camera::PinholeCamera tum1_camera() {
  camera::PinholeCamera c;
  c.name = "tum1";
  c.width = 640;
  c.height = 480;
  c.fx = 517.306408;
  c.fy = 516.469215;
  c.cx = 318.643040;
  c.cy = 255.313989;
  c.distortion = {0.262383, -0.953104, -0.005358, 0.002628, 1.163314};
  c.depth_factor = 5000.0;
  c.fps = 30.0;
  c.depth_time_offset_s = -0.020;  // as config/cameras/tum1.yaml
  return c;
}

void SequenceConfig::validate() const {
  if (name.empty() || name.find('/') != std::string::npos) {
    throw ConfigError::for_key("name",
                               fmt::format("must be a non-empty folder name (got '{}')", name));
  }
  if (background_dir.empty() && (frames < 1 || frames > 100000)) {
    throw ConfigError::for_key("frames", fmt::format("must be in 1..100000 (got {})", frames));
  }
  if (!(object_move_duration_s > 0) || !std::isfinite(object_move_start_s)) {
    throw ConfigError::for_key("object_move_duration_s",
                               fmt::format("must be > 0 (got {})", object_move_duration_s));
  }
  if (!(loop_turns >= 0.1 && loop_turns <= 10)) {
    throw ConfigError::for_key("loop_turns",
                               fmt::format("must be in [0.1, 10] (got {})", loop_turns));
  }
  if (!(rgb_noise_sigma >= 0 && rgb_noise_sigma <= 50)) {
    throw ConfigError::for_key("rgb_noise_sigma",
                               fmt::format("must be in [0, 50] (got {})", rgb_noise_sigma));
  }
  if (!(start_stamp_s >= 0 && start_stamp_s < 1e10)) {
    throw ConfigError::for_key("start_stamp_s",
                               fmt::format("must be in [0, 1e10) (got {})", start_stamp_s));
  }
  if (!(depth_stamp_jitter_s >= 0 && depth_stamp_jitter_s < 0.4 / camera.fps)) {
    throw ConfigError::for_key(
        "depth_stamp_jitter_s",
        fmt::format("must be in [0, 0.4 / fps) so RGB/depth pairs stay unambiguous (got {})",
                    depth_stamp_jitter_s));
  }
  if (!(walker_distance_near_m > 0.5 && walker_distance_far_m > 0.5)) {
    throw ConfigError::for_key("walker_distance_near_m", "walker distances must exceed 0.5 m");
  }
  if (background_dir.empty() && !void_boxes_w.empty()) {
    throw ConfigError::for_key("void_boxes_w",
                               "only a composite has real content to leave unscored; use none");
  }
  for (std::size_t i = 0; i < void_boxes_w.size(); ++i) {
    const WorldBox& b = void_boxes_w[i];
    if (!b.min_w.allFinite() || !b.max_w.allFinite() ||
        (b.min_w.array() >= b.max_w.array()).any()) {
      throw ConfigError::for_key(fmt::format("void_boxes_w[{}]", i),
                                 "needs finite bounds with min < max on every axis");
    }
  }
  if (void_grow_px < 0 || void_grow_px > 50) {
    throw ConfigError::for_key("void_grow_px",
                               fmt::format("must be in 0..50 (got {})", void_grow_px));
  }
  camera.validate();
  if (!background_dir.empty()) background_camera.validate();
  if (background_dir.empty() && camera.has_distortion()) {
    throw ConfigError::for_key("camera.distortion",
                               "synthetic rooms render an undistorted camera; use zeros");
  }
  depth.validate();
}

nlohmann::json SequenceConfig::to_json() const {
  auto cam = [](const camera::PinholeCamera& c) {
    nlohmann::json j{{"name", c.name},
                     {"width", c.width},
                     {"height", c.height},
                     {"fx", c.fx},
                     {"fy", c.fy},
                     {"cx", c.cx},
                     {"cy", c.cy},
                     {"distortion", c.distortion},
                     {"depth_factor", c.depth_factor},
                     {"fps", c.fps}};
    if (c.depth_time_offset_s) j["depth_time_offset_s"] = *c.depth_time_offset_s;
    return j;
  };
  const nlohmann::json depth_model{{"enabled", depth.enabled},
                                   {"min_range_m", depth.min_range_m},
                                   {"max_range_m", depth.max_range_m},
                                   {"max_incidence_deg", depth.max_incidence_deg},
                                   {"sigma_base_m", depth.sigma_base_m},
                                   {"sigma_quadratic", depth.sigma_quadratic},
                                   {"sigma_offset_m", depth.sigma_offset_m},
                                   {"sigma_angular", depth.sigma_angular},
                                   {"disparity_fb_px_m", depth.disparity_fb_px_m},
                                   {"disparity_subpixel", depth.disparity_subpixel},
                                   {"edge_jump_m", depth.edge_jump_m},
                                   {"edge_jump_relative", depth.edge_jump_relative},
                                   {"edge_extra_probability", depth.edge_extra_probability}};
  if (!background_dir.empty()) {
    // A composite uses only these: the camera, motion, stamps and colour come from the real
    // sequence, and the room's settings (camera path, posters, box) do not apply. Until stop 15
    // a composite made from a room preset with --background listed that preset's settings too.
    nlohmann::json boxes = nlohmann::json::array();
    for (const WorldBox& b : void_boxes_w) {
      boxes.push_back({{"min_w", {b.min_w.x(), b.min_w.y(), b.min_w.z()}},
                       {"max_w", {b.max_w.x(), b.max_w.y(), b.max_w.z()}}});
    }
    return nlohmann::json{{"name", name},
                          {"kind", "composite"},
                          {"frames", frames},
                          {"seed", seed},
                          {"background_dir", background_dir},
                          {"background_camera", cam(background_camera)},
                          {"people_dir", people_dir},
                          {"walker_distance_near_m", walker_distance_near_m},
                          {"walker_distance_far_m", walker_distance_far_m},
                          {"depth", depth_model},  // the people's depth
                          {"void_boxes_w", boxes},
                          {"void_grow_px", void_grow_px}};
  }
  return nlohmann::json{{"name", name},
                        {"kind", "room"},
                        {"frames", frames},
                        {"seed", seed},
                        {"motion", to_string(motion)},
                        {"loop_turns", loop_turns},
                        {"people", to_string(people)},
                        {"moving_object", moving_object},
                        {"object_move_start_s", object_move_start_s},
                        {"object_move_duration_s", object_move_duration_s},
                        {"camera", cam(camera)},
                        {"depth", depth_model},
                        {"rgb_noise_sigma", rgb_noise_sigma},
                        {"start_stamp_s", start_stamp_s},
                        {"depth_stamp_jitter_s", depth_stamp_jitter_s},
                        {"people_dir", people_dir},
                        {"poster_images", poster_images}};
}

const std::vector<Preset>& presets() {
  static const std::vector<Preset> kPresets = [] {
    std::vector<Preset> out;
    auto add = [&](const std::string& name, const std::string& description, MotionType motion,
                   PeopleScenario people, int frames, std::uint64_t seed, bool object = false,
                   double object_start_s = 12.0) {
      Preset p;
      p.name = name;
      p.description = description;
      p.config.name = name;
      p.config.motion = motion;
      p.config.people = people;
      p.config.frames = frames;
      p.config.seed = seed;
      p.config.moving_object = object;
      p.config.object_move_start_s = object_start_s;
      out.push_back(p);
    };
    using M = MotionType;
    using P = PeopleScenario;
    add("syn_walking_xyz", "two people walking; camera translates along x, y, z (fr3 walking_xyz)",
        M::kXyz, P::kWalking, 859, 101);
    add("syn_walking_static", "two people walking; camera nearly still (fr3 walking_static)",
        M::kStatic, P::kWalking, 743, 102);
    add("syn_walking_rpy", "two people walking; camera rotates roll/pitch/yaw (fr3 walking_rpy)",
        M::kRpy, P::kWalking, 900, 103);
    add("syn_walking_halfsphere",
        "two people walking; camera on a 1 m half-sphere (fr3 walking_halfsphere)", M::kHalfsphere,
        P::kWalking, 900, 104);
    add("syn_sitting_static",
        "two people seated at the desk, small motions; a box is moved at 12 s (fr3 sitting_static)",
        M::kStatic, P::kSitting, 707, 105, true, 12.0);
    add("syn_sitting_halfsphere",
        "two people seated at the desk; camera on a half-sphere; a box is moved at 16 s "
        "(fr3 sitting_halfsphere)",
        M::kHalfsphere, P::kSitting, 900, 106, true, 16.0);
    add("syn_desk_person",
        "a person enters after 18 s and then moves little; a box is moved at 25 s "
        "(fr2 desk_with_person)",
        M::kXyz, P::kDeskPerson, 900, 107, true, 25.0);
    add("syn_static_xyz", "static room control, xyz motion", M::kXyz, P::kNone, 800, 111);
    add("syn_static_static", "static room control, nearly still camera", M::kStatic, P::kNone, 800,
        112);
    add("syn_static_rpy", "static room control, rpy motion", M::kRpy, P::kNone, 800, 113);
    add("syn_static_halfsphere", "static room control, half-sphere motion", M::kHalfsphere,
        P::kNone, 800, 114);
    // 1.2 turns at 900 frames per turn: the last 180 frames revisit the start, so that several
    // consecutive keyframes see the mapped place again (ORB-SLAM2's loop consistency rule).
    add("syn_static_loop",
        "static room; the camera walks around the room, returns to its start and goes on for a "
        "fifth of a turn (loop closure)",
        M::kLoop, P::kNone, 1080, 115);
    out.back().config.loop_turns = 1.2;
    add("composite_fr1_rpy_walking",
        "real TUM fr1_rpy frames with two real people walking sideways in front of the desk",
        M::kStatic, P::kWalking, 0, 121);
    out.back().background_in_shared = "data/tum/rgbd_dataset_freiburg1_rpy";
    // The man sitting at the far desk of fr1_rpy (motion-capture frame): placed by hand around
    // his measured points and checked on the frames (docs/synthetic.md, "Void").
    out.back().config.void_boxes_w = {{Vec3d(-1.07, 0.37, 0.60), Vec3d(-0.62, 1.04, 1.60)}};
    return out;
  }();
  return kPresets;
}

const Preset& find_preset(const std::string& name) {
  std::string names;
  for (const auto& p : presets()) {
    if (p.name == name) return p;
    names += (names.empty() ? "" : ", ") + p.name;
  }
  throw ConfigError::for_key("preset", fmt::format("unknown preset '{}' (known: {})", name, names));
}

}  // namespace ddl::synthetic
