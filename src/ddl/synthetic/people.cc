#include "ddl/synthetic/people.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ddl/core/error.h"
#include "ddl/synthetic/procedural.h"

namespace ddl::synthetic {
namespace fs = std::filesystem;
namespace {

constexpr double kSittingCrop = 0.58;  // fraction of the body (from the top) a seated person shows

std::string mask_for(const fs::path& image) {
  return (image.parent_path().parent_path() / "masks" / image.stem()).string() + ".png";
}

/// Colours outside the mask are replaced by a smooth extension of the person's colours, so the
/// bilinear/mip filtering at the silhouette never picks up the photo's background.
cv::Mat bleed_colors(const cv::Mat& bgr, const cv::Mat& mask) {
  cv::Mat m;
  mask.convertTo(m, CV_32F, 1.0 / 255.0);
  cv::Mat f;
  bgr.convertTo(f, CV_32FC3);
  cv::Mat m3;
  cv::merge(std::vector<cv::Mat>{m, m, m}, m3);
  cv::Mat num = f.mul(m3);
  cv::Mat den = m3.clone();
  cv::GaussianBlur(num, num, cv::Size(0, 0), 6.0);
  cv::GaussianBlur(den, den, cv::Size(0, 0), 6.0);
  cv::Mat fill = num / cv::max(den, 1e-4);
  cv::Mat out = f.mul(m3) + fill.mul(cv::Scalar::all(1.0) - m3);
  cv::Mat out8;
  out.convertTo(out8, CV_8UC3);
  return out8;
}

void add_person_textures(Scene& scene, const cv::Mat& bgr_in, const cv::Mat& mask_in,
                         const std::string& source, PersonAppearance& out) {
  cv::Mat mask;
  cv::threshold(mask_in, mask, 127, 255, cv::THRESH_BINARY);
  const cv::Rect box = cv::boundingRect(mask);
  if (box.area() == 0) throw InputError::at(source, "the person mask is empty");
  const cv::Mat crop = bleed_colors(bgr_in(box), mask(box));
  const cv::Mat crop_mask = mask(box).clone();
  out.texture = scene.add_texture(make_texture(crop, crop_mask, source));
  out.aspect = static_cast<double>(box.width) / box.height;
  const int rows = std::max(1, static_cast<int>(box.height * kSittingCrop));
  const cv::Rect top(0, 0, box.width, rows);
  out.sitting_texture = scene.add_texture(make_texture(crop(top), crop_mask(top), source));
  out.sitting_aspect = static_cast<double>(box.width) / rows;
  out.source = source;
}

}  // namespace

std::vector<std::string> list_person_photos(const std::string& people_dir) {
  std::vector<std::string> out;
  std::error_code ec;
  const fs::path images = fs::path(people_dir) / "images";
  if (people_dir.empty() || !fs::is_directory(images, ec)) return out;
  for (const auto& entry : fs::directory_iterator(images, ec)) {
    const fs::path p = entry.path();
    if (p.extension() != ".jpg" && p.extension() != ".png") continue;
    if (fs::exists(mask_for(p), ec)) out.push_back(p.string());
  }
  std::sort(out.begin(), out.end());
  return out;
}

std::vector<PersonAppearance> load_people(Scene& scene, const std::string& people_dir, int count,
                                          Rng& rng) {
  std::vector<std::string> photos = list_person_photos(people_dir);
  std::vector<PersonAppearance> people;
  for (int i = 0; i < count; ++i) {
    PersonAppearance person;
    if (!photos.empty()) {
      const auto k =
          static_cast<std::size_t>(rng.uniform_int(0, static_cast<int>(photos.size()) - 1));
      const std::string path = photos[k];
      photos.erase(photos.begin() + static_cast<std::ptrdiff_t>(k));
      const cv::Mat bgr = cv::imread(path, cv::IMREAD_COLOR);
      if (bgr.empty()) throw InputError::at(path, "cannot decode the person photo");
      const std::string mask_path = mask_for(path);
      const cv::Mat mask = cv::imread(mask_path, cv::IMREAD_GRAYSCALE);
      if (mask.empty()) throw InputError::at(mask_path, "cannot decode the person mask");
      if (mask.size() != bgr.size()) {
        throw InputError::at(mask_path, fmt::format("mask is {}x{} but the photo is {}x{}",
                                                    mask.cols, mask.rows, bgr.cols, bgr.rows));
      }
      add_person_textures(scene, bgr, mask, path, person);
    } else {
      Rng r = rng.fork(static_cast<std::uint64_t>(i));
      cv::Mat bgr;
      cv::Mat alpha;
      make_person_silhouette(cv::Size(300, 820), r, bgr, alpha);
      add_person_textures(scene, bgr, alpha, "procedural:silhouette", person);
    }
    people.push_back(person);
  }
  return people;
}

PersonState person_state(const PersonTrack& track, double t) {
  PersonState s;
  Rng rng(track.seed);
  const double p1 = rng.uniform(0, 2 * M_PI);
  const double p2 = rng.uniform(0, 2 * M_PI);
  const double p3 = rng.uniform(0, 2 * M_PI);
  switch (track.type) {
    case PersonTrackType::kWalking: {
      const double omega = 2 * M_PI / track.period_s;
      const double w = 0.5 - 0.5 * std::cos(omega * t + track.phase);
      const Vec3d dir = (track.b_w - track.a_w).normalized();
      const Vec3d side(-dir.y(), dir.x(), 0);
      s.visible = true;
      s.foot_w = track.a_w + w * (track.b_w - track.a_w) + side * 0.15 * std::sin(0.7 * t + p1);
      // Vertical bob at twice the step frequency (about 2 steps per second), in phase with speed.
      s.height_m = track.height_m + 0.015 * std::sin(2 * M_PI * 1.8 * t + p2);
      s.sway = 0.0;
      break;
    }
    case PersonTrackType::kSitting: {
      s.visible = true;
      s.foot_w =
          track.a_w + Vec3d(0.04 * std::sin(0.31 * t + p1), 0.03 * std::sin(0.23 * t + p2), 0.0);
      s.height_m = track.height_m * kSittingCrop;
      s.sway = 0.035 * std::sin(0.9 * t + p3) + 0.015 * std::sin(2.3 * t + p1);
      break;
    }
    case PersonTrackType::kAppearing: {
      if (t < track.appear_s) break;
      const double x = std::min(1.0, (t - track.appear_s) / track.walk_s);
      const double smooth = x * x * x * (10 + x * (-15 + 6 * x));  // C2 smootherstep
      s.visible = true;
      s.foot_w = track.a_w + smooth * (track.b_w - track.a_w) +
                 Vec3d(0.03 * std::sin(0.4 * t + p1), 0.02 * std::sin(0.3 * t + p2), 0.0) * x;
      s.height_m = track.height_m;
      s.sway = 0.02 * std::sin(0.8 * t + p3) * x;
      break;
    }
  }
  return s;
}

Surface person_billboard(const PersonTrack& track, const PersonAppearance& appearance,
                         const PersonState& state, const Vec3d& camera_w, int entity) {
  const bool sitting = track.type == PersonTrackType::kSitting;
  const double aspect = sitting ? appearance.sitting_aspect : appearance.aspect;
  Vec3d to_camera = camera_w - state.foot_w;
  to_camera.z() = 0;
  if (to_camera.norm() < 1e-6) to_camera = Vec3d::UnitX();
  const double h = state.height_m;
  Surface s =
      make_rect(state.foot_w + Vec3d(0, 0, h / 2), to_camera.normalized(), Vec3d::UnitZ(),
                h * aspect, h, sitting ? appearance.sitting_texture : appearance.texture, entity);
  s.shade = 1.0f;
  s.sway = static_cast<float>(state.sway);
  return s;
}

}  // namespace ddl::synthetic
