// The composite source: real TUM frames with real people rendered into them (docs/synthetic.md).

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ddl/core/error.h"
#include "ddl/io/trajectory_io.h"
#include "ddl/io/tum_dataset.h"
#include "ddl/synthetic/depth_model.h"
#include "ddl/synthetic/people.h"
#include "ddl/synthetic/renderer.h"
#include "ddl/synthetic/sequence_internal.h"

namespace ddl::synthetic {
namespace {

/// Ground-truth pose at `stamp` by linear/slerp interpolation; false outside the trajectory.
bool interpolate_pose(const io::Trajectory& gt, double stamp, SE3& out) {
  if (gt.empty() || stamp < gt.front().timestamp_s || stamp > gt.back().timestamp_s) return false;
  const auto it =
      std::lower_bound(gt.begin(), gt.end(), stamp,
                       [](const io::StampedPose& p, double s) { return p.timestamp_s < s; });
  if (it == gt.begin()) {
    out = it->T_w_c();
    return true;
  }
  const auto prev = it - 1;
  const double span = it->timestamp_s - prev->timestamp_s;
  const double s = span > 0 ? (stamp - prev->timestamp_s) / span : 0.0;
  out = interpolate(prev->T_w_c(), it->T_w_c(), s);
  return true;
}

/// The void mask of a composite frame: real pixels whose surface point (`depth_m`, the measured
/// depth with holes taken from the nearest measured pixel, along the renderer's ray of the pixel,
/// camera -> world by `T_w_c`) lies in one of `boxes`, grown by `grow_px`, minus the dynamic mask
/// (a person drawn in front is scored).
cv::Mat void_mask_of(const cv::Mat& depth_m, const Renderer& renderer, const SE3& T_w_c,
                     const std::vector<WorldBox>& boxes, int grow_px, const cv::Mat& dynamic_mask) {
  cv::Mat mask(depth_m.size(), CV_8UC1, cv::Scalar(0));
  for (int v = 0; v < depth_m.rows; ++v) {
    const float* z = depth_m.ptr<float>(v);
    auto* out = mask.ptr<std::uint8_t>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      if (z[u] <= 0.0f) continue;
      const Vec3d p_w = T_w_c * (static_cast<double>(z[u]) * renderer.ray(u, v));
      for (const WorldBox& box : boxes) {
        if (box.contains(p_w)) {
          out[u] = 255;
          break;
        }
      }
    }
  }
  if (grow_px > 0) {
    cv::dilate(mask, mask,
               cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * grow_px + 1, 2 * grow_px + 1}));
  }
  mask.setTo(0, dynamic_mask);
  return mask;
}

/// The background sequence's own readings are copied into the composite (accelerometer()).
io::SequenceOptions with_accelerometer() {
  io::SequenceOptions options;
  options.read_accelerometer = true;
  return options;
}

class CompositeSequence final : public SequenceSource {
 public:
  explicit CompositeSequence(const SequenceConfig& config)
      : config_(config),
        dataset_(config.background_dir, config.background_camera, with_accelerometer()),
        renderer_(config.background_camera) {
    const auto gt_path = dataset_.groundtruth_path();
    if (!gt_path) {
      throw InputError::at(config.background_dir,
                           "a composite needs the sequence's groundtruth.txt (camera poses)");
    }
    groundtruth_ = io::read_tum_trajectory(*gt_path);
    for (std::size_t i = 0; i < dataset_.pairs().size(); ++i) {
      SE3 pose;
      if (!interpolate_pose(groundtruth_, dataset_.pairs()[i].rgb_timestamp_s, pose)) continue;
      frames_.push_back(i);
      poses_.push_back(pose);
      if (config.frames > 0 && static_cast<int>(frames_.size()) >= config.frames) break;
    }
    if (frames_.empty()) {
      throw InputError::at(*gt_path, "no RGB-D pair lies inside the ground-truth time range");
    }
    // Where the camera looks on average: the walkers move sideways across that direction.
    Vec3d mean_position = Vec3d::Zero();
    Vec3d mean_forward = Vec3d::Zero();
    for (const auto& p : poses_) {
      mean_position += p.translation();
      mean_forward += p.rotation().col(2);
    }
    mean_position /= static_cast<double>(poses_.size());
    Vec3d forward(mean_forward.x(), mean_forward.y(), 0.0);
    if (forward.norm() < 1e-6) forward = Vec3d::UnitX();
    forward.normalize();
    const Vec3d side(-forward.y(), forward.x(), 0.0);
    const Vec3d foot(mean_position.x(), mean_position.y(), 0.0);  // TUM mocap floor: z = 0
    t0_ = dataset_.pairs()[frames_.front()].rgb_timestamp_s;

    Rng rng(config.seed);
    Rng people_rng = rng.fork(2);
    appearances_ = load_people(scene_, config.people_dir, 2, people_rng);
    const double distances[2] = {config.walker_distance_near_m, config.walker_distance_far_m};
    const double half_widths[2] = {0.9, 1.2};
    for (int k = 0; k < 2; ++k) {
      PersonTrack track;
      track.type = PersonTrackType::kWalking;
      track.appearance = k;
      track.height_m = people_rng.uniform(1.6, 1.9);
      track.seed = people_rng.next();
      const Vec3d centre = foot + distances[k] * forward;
      const double sign = k == 0 ? 1.0 : -1.0;
      track.a_w = centre - sign * half_widths[k] * side;
      track.b_w = centre + sign * half_widths[k] * side;
      track.period_s = people_rng.uniform(6.0, 8.0);
      track.phase = people_rng.uniform(0, 2 * M_PI);
      tracks_.push_back(track);
    }
  }

  const SequenceConfig& config() const override { return config_; }
  const camera::PinholeCamera& camera() const override { return config_.background_camera; }
  std::size_t frame_count() const override { return frames_.size(); }

  FrameData render_frame(std::size_t index) const override {
    const io::FramePair& pair = dataset_.pairs().at(frames_.at(index));
    FrameData f;
    f.index = index;
    f.rgb_stamp_s = pair.rgb_timestamp_s;
    f.depth_stamp_s = pair.depth_timestamp_s;
    f.T_w_c = poses_[index];
    f.background_rgb = cv::imread(pair.rgb_path, cv::IMREAD_COLOR);
    if (f.background_rgb.empty()) throw InputError::at(pair.rgb_path, "cannot decode the image");
    f.background_depth_raw = cv::imread(pair.depth_path, cv::IMREAD_UNCHANGED);
    if (f.background_depth_raw.type() != CV_16UC1) {
      throw InputError::at(pair.depth_path, "expected a 16-bit single-channel depth PNG");
    }
    const camera::PinholeCamera& cam = config_.background_camera;
    if (f.background_rgb.cols != cam.width || f.background_rgb.rows != cam.height ||
        f.background_depth_raw.size() != f.background_rgb.size()) {
      throw InputError::at(pair.rgb_path, fmt::format("frame size differs from the camera's {}x{}",
                                                      cam.width, cam.height));
    }
    // The people as the colour camera saw them (RGB, the truth mask) and as the depth sensor
    // did: a camera whose depth was captured at another instant (depth_time_offset_s, such as
    // tum1's) saw them, and the real scene, from another pose and at another moment.
    const double t_rgb = pair.rgb_timestamp_s;
    const double t_depth =
        cam.depth_time_offset_s ? pair.depth_timestamp_s + *cam.depth_time_offset_s : t_rgb;
    SE3 T_w_depth = f.T_w_c;
    if (t_depth != t_rgb && !interpolate_pose(groundtruth_, t_depth, T_w_depth)) {
      T_w_depth = f.T_w_c;  // beyond the ground truth's ends: the colour pose
    }
    const auto people_at = [&](double stamp_s, const SE3& T_w_c, bool record) {
      std::vector<Surface> surfaces;
      for (std::size_t k = 0; k < tracks_.size(); ++k) {
        const PersonState state = person_state(tracks_[k], stamp_s - t0_);
        if (record) {
          f.entities.push_back({static_cast<int>(k) + 1, "person", true, true, state.foot_w});
        }
        surfaces.push_back(person_billboard(tracks_[k], appearances_[k], state, T_w_c.translation(),
                                            static_cast<int>(k) + 1));
      }
      return surfaces;
    };
    const std::vector<Surface> surfaces = people_at(t_rgb, f.T_w_c, true);
    const PreparedSurfaces prepared(surfaces, scene_.textures, f.T_w_c.inverse());
    RenderBuffers people = renderer_.make_buffers();
    renderer_.rasterize(prepared, 0, surfaces.size(), people);

    // Depth test against the real surface: a person pixel exists where it is nearer than it.
    // Where the sensor measured nothing (a black monitor screen, IR shadows) the surface is taken
    // from the nearest measured pixel, so the monitor still hides who walks behind it.
    f.background_depth_raw.convertTo(f.background_depth_exact_m, CV_32FC1, 1.0 / cam.depth_factor);
    const cv::Mat surface_m = fill_missing_depth_nearest(f.background_depth_exact_m);
    // Marks the person pixels of `buffers` nearer than the real surface in `mask` (and the
    // entity ids); the others become id -1. Returns how many there are.
    const auto visible_people = [&](RenderBuffers& buffers, const std::vector<Surface>& list,
                                    cv::Mat& mask, cv::Mat* entity) {
      mask = cv::Mat(buffers.id.size(), CV_8UC1, cv::Scalar(0));
      std::size_t count = 0;
      for (int v = 0; v < buffers.id.rows; ++v) {
        int* id = buffers.id.ptr<int>(v);
        const float* z = buffers.depth_m.ptr<float>(v);
        const float* real = surface_m.ptr<float>(v);
        auto* m = mask.ptr<unsigned char>(v);
        for (int u = 0; u < buffers.id.cols; ++u) {
          if (id[u] < 0) continue;
          if (real[u] > 0.0f && z[u] >= real[u]) {
            id[u] = -1;  // hidden behind the real scene
            continue;
          }
          m[u] = 255;
          if (entity != nullptr) {
            entity->at<int>(v, u) = list[static_cast<std::size_t>(id[u])].entity;
          }
          ++count;
        }
      }
      return count;
    };
    f.entity = cv::Mat(people.id.size(), CV_32SC1, cv::Scalar(0));
    const std::size_t dynamic_pixels = visible_people(people, surfaces, f.dynamic_mask, &f.entity);
    if (!config_.void_boxes_w.empty()) {
      f.void_mask = void_mask_of(surface_m, renderer_, f.T_w_c, config_.void_boxes_w,
                                 config_.void_grow_px, f.dynamic_mask);
    }
    f.rgb = f.background_rgb.clone();
    cv::Mat cos_incidence;
    renderer_.shade(prepared, people, 0, f.rgb, cos_incidence);

    // The people the depth sensor saw: the same ones without a depth offset.
    cv::Mat depth_people_mask = f.dynamic_mask;
    RenderBuffers depth_people = people;
    cv::Mat depth_cos = cos_incidence;
    if (t_depth != t_rgb) {
      const std::vector<Surface> at_depth = people_at(t_depth, T_w_depth, false);
      const PreparedSurfaces prepared_depth(at_depth, scene_.textures, T_w_depth.inverse());
      depth_people = renderer_.make_buffers();
      renderer_.rasterize(prepared_depth, 0, at_depth.size(), depth_people);
      visible_people(depth_people, at_depth, depth_people_mask, nullptr);
      cv::Mat scratch = f.background_rgb.clone();
      renderer_.shade(prepared_depth, depth_people, 0, scratch, depth_cos);
    }
    f.depth_dynamic_mask = depth_people_mask;
    f.depth_exact_m = f.background_depth_exact_m.clone();
    depth_people.depth_m.copyTo(f.depth_exact_m, depth_people_mask);
    // Sensor model on the combined depth; only person pixels take the modelled value, the real
    // measurements stay, except where they become the far side of a person's edge (shadow).
    cv::Mat combined_cos(people.id.size(), CV_32FC1, cv::Scalar(1.0f));
    depth_cos.copyTo(combined_cos, depth_people_mask);
    const cv::Mat modelled = apply_depth_model(f.depth_exact_m, combined_cos, config_.depth,
                                               cam.depth_factor, config_.seed, index);
    f.depth_raw = f.background_depth_raw.clone();
    modelled.copyTo(f.depth_raw, depth_people_mask);
    const float jump = static_cast<float>(config_.depth.edge_jump_m);
    for (int v = 0; v < people.id.rows; ++v) {
      auto* out = f.depth_raw.ptr<std::uint16_t>(v);
      const auto* mask = depth_people_mask.ptr<unsigned char>(v);
      const float* real = f.depth_exact_m.ptr<float>(v);
      for (int u = 0; u < people.id.cols; ++u) {
        if (mask[u] || out[u] == 0) continue;
        for (int dv = -1; dv <= 1; ++dv) {
          for (int du = -1; du <= 1; ++du) {
            const int vv = v + dv;
            const int uu = u + du;
            if (vv < 0 || uu < 0 || vv >= people.id.rows || uu >= people.id.cols) continue;
            if (depth_people_mask.at<unsigned char>(vv, uu) &&
                real[u] - f.depth_exact_m.at<float>(vv, uu) > jump) {
              out[u] = 0;
            }
          }
        }
      }
    }
    f.dynamic_fraction = static_cast<double>(dynamic_pixels) / static_cast<double>(f.rgb.total());
    return f;
  }

  io::Trajectory groundtruth() const override { return groundtruth_; }

  std::vector<io::AccelerometerSample> accelerometer() const override {
    std::vector<io::AccelerometerSample> out;
    if (!dataset_.accelerometer()) return out;
    const double first = dataset_.pairs()[frames_.front()].rgb_timestamp_s - kAccelerometerMarginS;
    const double last = dataset_.pairs()[frames_.back()].rgb_timestamp_s + kAccelerometerMarginS;
    for (const io::AccelerometerSample& s : dataset_.accelerometer()->samples()) {
      if (s.timestamp_s >= first && s.timestamp_s <= last) out.push_back(s);
    }
    return out;
  }

  nlohmann::json description() const override {
    nlohmann::json people = nlohmann::json::array();
    for (std::size_t k = 0; k < tracks_.size(); ++k) {
      const auto& tr = tracks_[k];
      people.push_back({{"entity", static_cast<int>(k) + 1},
                        {"photo", appearances_[k].source},
                        {"track", "walking"},
                        {"height_m", tr.height_m},
                        {"a_w", {tr.a_w.x(), tr.a_w.y(), tr.a_w.z()}},
                        {"b_w", {tr.b_w.x(), tr.b_w.y(), tr.b_w.z()}},
                        {"period_s", tr.period_s}});
    }
    return {{"kind", "composite"},
            {"background_sequence", config_.background_dir},
            {"associations", dataset_.association_description()},
            {"world_frame", "the sequence's ground-truth (motion capture) frame; floor z = 0"},
            {"people", people},
            {"depth_instant",
             config_.background_camera.depth_time_offset_s
                 ? "people are drawn into the depth image as the depth sensor saw them: at the "
                   "depth's capture instant (its stamp plus the camera's depth_time_offset_s), "
                   "from the ground-truth pose then; into the colour image and dynamic_mask at "
                   "the colour instant"
                 : "people are drawn into the depth and colour images at the colour instant "
                   "(the camera has no depth_time_offset_s)"},
            {"distortion",
             "people are rendered into the distorted images: every pixel's ray is the inverse of "
             "the camera's Brown-Conrady model, so undistorting the frame gives a correct "
             "pinhole image of the person"}};
  }

 private:
  SequenceConfig config_;
  io::TumDataset dataset_;
  Renderer renderer_;
  Scene scene_;  // textures of the people only
  io::Trajectory groundtruth_;
  std::vector<std::size_t> frames_;  // indices into dataset_.pairs() with a ground-truth pose
  AlignedVector<SE3> poses_;
  double t0_ = 0.0;
  std::vector<PersonAppearance> appearances_;
  std::vector<PersonTrack> tracks_;
};

}  // namespace

std::unique_ptr<SequenceSource> make_composite_sequence(const SequenceConfig& config) {
  return std::make_unique<CompositeSequence>(config);
}

}  // namespace ddl::synthetic
