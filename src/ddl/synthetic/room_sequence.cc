// The synthetic-room source: renders the room, its people and the movable box along a motion.

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <set>

#include "ddl/synthetic/people.h"
#include "ddl/synthetic/procedural.h"
#include "ddl/synthetic/random.h"
#include "ddl/synthetic/renderer.h"
#include "ddl/synthetic/scene.h"
#include "ddl/synthetic/sequence.h"
#include "ddl/synthetic/sequence_internal.h"

namespace ddl::synthetic {
namespace {

/// The movable box: where it starts and ends on the desk.
struct ObjectPath {
  Vec3d from_w = Vec3d(2.5, 3.62, 0.75);  // bottom centre, on the desk top
  Vec3d to_w = Vec3d(3.45, 3.78, 0.75);
  double yaw_from = 0.2;
  double yaw_to = 0.95;
  double lift_m = 0.25;  // height of the carrying arc
};

class RoomSequence final : public SequenceSource {
 public:
  explicit RoomSequence(const SequenceConfig& config) : config_(config), renderer_(config.camera) {
    Rng rng(config.seed);
    Rng room_rng = rng.fork(1);
    Rng people_rng = rng.fork(2);
    Rng object_rng = rng.fork(3);
    RoomOptions options;
    options.poster_images = config.poster_images;
    scene_ = build_room(options, layout_, room_rng);

    motion_.type = config.motion;
    motion_.seed = hash2(config.seed, 0x6d07);
    motion_.base_position_w = layout_.view_position_w;
    motion_.look_at_w = layout_.view_target_w;
    if (config.people == PeopleScenario::kSitting) {
      // Closer to the desk, as in TUM's sitting sequences, so the seated people fill more of the
      // image.
      motion_.base_position_w = Vec3d(3.0, 2.0, 1.4);
      motion_.look_at_w = Vec3d(3.05, 4.3, 0.95);
    }
    motion_.loop_period_s = std::max(1, config.frames - 1) / config.camera.fps / config.loop_turns;

    const int count = config.people == PeopleScenario::kNone         ? 0
                      : config.people == PeopleScenario::kDeskPerson ? 1
                                                                     : 2;
    appearances_ = load_people(scene_, config.people_dir, count, people_rng);
    const double duration_s = config.frames / config.camera.fps;
    for (int k = 0; k < count; ++k) {
      PersonTrack track;
      track.appearance = k;
      track.height_m = people_rng.uniform(1.6, 1.9);
      track.seed = people_rng.next();
      switch (config.people) {
        case PeopleScenario::kWalking:
          track.type = PersonTrackType::kWalking;
          // Near line 1 m in front of the base view, far line in front of the desk.
          // Ends just outside the base view, so both are in view most of the time.
          track.a_w = k == 0 ? Vec3d(1.7, 2.1, 0) : Vec3d(4.7, 3.0, 0);
          track.b_w = k == 0 ? Vec3d(4.3, 2.1, 0) : Vec3d(1.3, 3.0, 0);
          track.period_s = people_rng.uniform(7.0, 9.0);
          track.phase = people_rng.uniform(0, 2 * M_PI);
          break;
        case PeopleScenario::kSitting:
          track.type = PersonTrackType::kSitting;
          track.a_w = Vec3d(k == 0 ? 2.65 : 3.4, 4.45, 0.47);
          break;
        case PeopleScenario::kDeskPerson:
          track.type = PersonTrackType::kAppearing;
          track.a_w = Vec3d(0.7, 4.45, 0);
          track.b_w = Vec3d(2.9, 4.45, 0);
          track.appear_s = 0.6 * duration_s;
          track.walk_s = 3.0;
          break;
        case PeopleScenario::kNone:
          break;
      }
      tracks_.push_back(track);
    }
    if (config.moving_object) {
      const Vec3d size(0.26, 0.18, 0.13);
      std::vector<int> sides;
      for (int i = 0; i < 4; ++i) {
        const double w = (i % 2 == 0) ? size.y() : size.x();
        sides.push_back(scene_.add_texture(make_texture(
            make_cardboard_texture(
                cv::Size(static_cast<int>(w / 0.0015), static_cast<int>(size.z() / 0.0015)), 0.0015,
                object_rng),
            {}, "procedural:cardboard")));
      }
      const int top = scene_.add_texture(make_texture(
          make_cardboard_texture(
              cv::Size(static_cast<int>(size.x() / 0.0015), static_cast<int>(size.y() / 0.0015)),
              0.0015, object_rng),
          {}, "procedural:cardboard"));
      object_local_ = make_box(Vec3d::Zero(), size, 0.0, sides, top, count + 1);
    }
  }

  const SequenceConfig& config() const override { return config_; }
  const camera::PinholeCamera& camera() const override { return config_.camera; }
  std::size_t frame_count() const override { return static_cast<std::size_t>(config_.frames); }

  double time_s(std::size_t i) const {
    return static_cast<double>(stamp_offset_us(i, config_.camera.fps)) * 1e-6;
  }

  /// Object bottom centre and yaw at time t; `moving_or_moved` from the start of the carry on.
  void object_pose(double t, Vec3d& position, double& yaw, bool& moved) const {
    const double x =
        std::clamp((t - config_.object_move_start_s) / config_.object_move_duration_s, 0.0, 1.0);
    const double s = x * x * x * (10 + x * (-15 + 6 * x));
    position = object_.from_w + s * (object_.to_w - object_.from_w) +
               Vec3d(0, 0, object_.lift_m * std::sin(M_PI * s));
    yaw = object_.yaw_from + s * (object_.yaw_to - object_.yaw_from);
    moved = t >= config_.object_move_start_s;
  }

  FrameData render_frame(std::size_t index) const override {
    FrameData f;
    f.index = index;
    const double t = time_s(index);
    f.rgb_stamp_s = rgb_stamp(config_, index);
    f.depth_stamp_s = depth_stamp(config_, index, f.rgb_stamp_s);
    f.T_w_c = camera_pose(motion_, t);
    const SE3 T_c_w = f.T_w_c.inverse();
    const Vec3d camera_w = f.T_w_c.translation();

    // Static surfaces first, then the surfaces dynamic in this frame.
    std::vector<Surface> surfaces = scene_.surfaces;
    std::vector<Surface> dynamic;
    for (std::size_t k = 0; k < tracks_.size(); ++k) {
      const PersonState state = person_state(tracks_[k], t);
      EntityState e{static_cast<int>(k) + 1, "person", state.visible, state.visible, state.foot_w};
      f.entities.push_back(e);
      if (!state.visible) continue;
      dynamic.push_back(
          person_billboard(tracks_[k], appearances_[k], state, camera_w, static_cast<int>(k) + 1));
    }
    if (!object_local_.empty()) {
      Vec3d position;
      double yaw = 0;
      bool moved = false;
      object_pose(t, position, yaw, moved);
      const Mat3d R = so3_exp(Vec3d(0, 0, yaw));
      for (Surface s : object_local_) {
        s.origin_w = R * s.origin_w + position;
        s.u_w = R * s.u_w;
        s.v_w = R * s.v_w;
        s.shade = plane_shade(s.front_normal());
        (moved ? dynamic : surfaces).push_back(s);
      }
      f.entities.push_back({static_cast<int>(tracks_.size()) + 1, "object", true, moved,
                            position + Vec3d(0, 0, 0.065)});
    }
    const std::size_t n_static = surfaces.size();
    surfaces.insert(surfaces.end(), dynamic.begin(), dynamic.end());
    const PreparedSurfaces prepared(surfaces, scene_.textures, T_c_w);

    RenderBuffers background = renderer_.make_buffers();
    renderer_.rasterize(prepared, 0, n_static, background);
    RenderBuffers foreground = background.clone();
    renderer_.rasterize(prepared, n_static, surfaces.size(), foreground);

    cv::Mat bg_cos;
    renderer_.shade(prepared, background, 0, f.background_rgb, bg_cos);
    add_rgb_noise(f.background_rgb, config_.rgb_noise_sigma, config_.seed, index);

    f.dynamic_mask = cv::Mat(foreground.id.size(), CV_8UC1, cv::Scalar(0));
    f.entity = cv::Mat(foreground.id.size(), CV_32SC1, cv::Scalar(-1));
    std::size_t dynamic_pixels = 0;
    for (int v = 0; v < foreground.id.rows; ++v) {
      const int* id = foreground.id.ptr<int>(v);
      auto* mask = f.dynamic_mask.ptr<unsigned char>(v);
      int* ent = f.entity.ptr<int>(v);
      for (int u = 0; u < foreground.id.cols; ++u) {
        if (id[u] < 0) continue;
        ent[u] = surfaces[static_cast<std::size_t>(id[u])].entity;
        if (static_cast<std::size_t>(id[u]) >= n_static) {
          mask[u] = 255;
          ++dynamic_pixels;
        }
      }
    }
    f.depth_dynamic_mask = f.dynamic_mask;  // depth and colour share one instant here
    // The frame is the background except on dynamic pixels, which are shaded and get the same
    // per-pixel noise they would get anyway.
    f.rgb = f.background_rgb.clone();
    cv::Mat fg_cos = bg_cos.clone();
    renderer_.shade(prepared, foreground, static_cast<int>(n_static), f.rgb, fg_cos);
    add_rgb_noise(f.rgb, config_.rgb_noise_sigma, config_.seed, index, f.dynamic_mask);

    f.depth_exact_m = foreground.depth_m;
    f.background_depth_exact_m = background.depth_m;
    f.background_depth_raw = apply_depth_model(background.depth_m, bg_cos, config_.depth,
                                               config_.camera.depth_factor, config_.seed, index);
    if (dynamic_pixels == 0) {
      f.depth_raw = f.background_depth_raw.clone();
    } else {
      f.depth_raw = apply_depth_model(foreground.depth_m, fg_cos, config_.depth,
                                      config_.camera.depth_factor, config_.seed, index);
    }
    f.dynamic_fraction = static_cast<double>(dynamic_pixels) / static_cast<double>(f.rgb.total());
    return f;
  }

  io::Trajectory groundtruth() const override {
    io::Trajectory out;
    for (std::size_t i = 0; i < frame_count(); ++i) {
      out.emplace_back(rgb_stamp(config_, i), camera_pose(motion_, time_s(i)));
    }
    return out;
  }

  std::vector<io::AccelerometerSample> accelerometer() const override {
    // Its own noise stream: the scene, people and object streams stay as they were.
    Rng noise(hash2(config_.seed, 0xacce1e));
    std::vector<io::AccelerometerSample> out;
    for (std::size_t i = 0; i < frame_count(); ++i) {
      out.push_back(
          {rgb_stamp(config_, i), kinect_accelerometer_reading(motion_, time_s(i), noise)});
    }
    return out;
  }

  nlohmann::json description() const override {
    std::set<std::string> sources;
    for (const auto& t : scene_.textures) sources.insert(t.source);
    nlohmann::json people = nlohmann::json::array();
    for (std::size_t k = 0; k < tracks_.size(); ++k) {
      const auto& tr = tracks_[k];
      people.push_back({{"entity", static_cast<int>(k) + 1},
                        {"photo", appearances_[k].source},
                        {"track", tr.type == PersonTrackType::kWalking   ? "walking"
                                  : tr.type == PersonTrackType::kSitting ? "sitting"
                                                                         : "appearing"},
                        {"height_m", tr.height_m},
                        {"a_w", {tr.a_w.x(), tr.a_w.y(), tr.a_w.z()}},
                        {"b_w", {tr.b_w.x(), tr.b_w.y(), tr.b_w.z()}},
                        {"period_s", tr.period_s},
                        {"appear_s", tr.appear_s}});
    }
    nlohmann::json j{
        {"kind", "synthetic_room"},
        {"world_frame", "x east, y north, z up, metres; floor z = 0"},
        {"room_min_w", {scene_.room_min.x(), scene_.room_min.y(), scene_.room_min.z()}},
        {"room_max_w", {scene_.room_max.x(), scene_.room_max.y(), scene_.room_max.z()}},
        {"static_surfaces", scene_.surfaces.size()},
        {"texture_sources", sources},
        {"people", people},
        {"billboards",
         "upright, bottom on the floor (seated: at seat height), turned about z "
         "to face the camera centre each frame"}};
    if (!object_local_.empty()) {
      const int id = static_cast<int>(tracks_.size()) + 1;
      j["object"] = {
          {"entity", id},
          {"size_m", {0.26, 0.18, 0.13}},
          {"from_bottom_centre_w", {object_.from_w.x(), object_.from_w.y(), object_.from_w.z()}},
          {"to_bottom_centre_w", {object_.to_w.x(), object_.to_w.y(), object_.to_w.z()}},
          {"yaw_from_rad", object_.yaw_from},
          {"yaw_to_rad", object_.yaw_to},
          {"move_start_s", config_.object_move_start_s},
          {"move_duration_s", config_.object_move_duration_s},
          {"convention",
           "static (in the background, not in the mask) before move_start_s; dynamic from then "
           "on, including after it was put down; the background then shows the scene without "
           "it"}};
    }
    return j;
  }

 private:
  SequenceConfig config_;
  Renderer renderer_;
  RoomLayout layout_;
  Scene scene_;
  MotionConfig motion_;
  std::vector<PersonAppearance> appearances_;
  std::vector<PersonTrack> tracks_;
  ObjectPath object_;
  std::vector<Surface> object_local_;
};

}  // namespace

std::unique_ptr<SequenceSource> make_room_sequence(const SequenceConfig& config) {
  return std::make_unique<RoomSequence>(config);
}

}  // namespace ddl::synthetic
