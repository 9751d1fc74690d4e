#include "ddl/synthetic/scene.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "ddl/synthetic/procedural.h"

namespace ddl::synthetic {
namespace {

/// Texture size in texels for a surface of the given metric size, capped at `max_px` per side
/// (the texel grows instead).
cv::Size texture_size(double width_m, double height_m, double texel_m, int max_px = 2048) {
  const double scale = std::max({1.0, width_m / texel_m / max_px, height_m / texel_m / max_px});
  return {std::max(8, static_cast<int>(std::lround(width_m / texel_m / scale))),
          std::max(8, static_cast<int>(std::lround(height_m / texel_m / scale)))};
}

double texel_for(const cv::Size& size, double width_m) { return width_m / size.width; }

enum class Kind { kWall, kFloor, kCeiling, kWood, kDesk, kShelf, kCardboard };

int add_procedural(Scene& scene, Kind kind, double width_m, double height_m, double texel_m,
                   Rng& rng) {
  const cv::Size size = texture_size(width_m, height_m, texel_m);
  const double t = texel_for(size, width_m);
  Rng r = rng.fork(static_cast<std::uint64_t>(scene.textures.size()));
  cv::Mat img;
  std::string name;
  switch (kind) {
    case Kind::kWall:
      img = make_wall_texture(size, t, r), name = "wall";
      break;
    case Kind::kFloor:
      img = make_floor_texture(size, t, r), name = "floor";
      break;
    case Kind::kCeiling:
      img = make_ceiling_texture(size, t, r), name = "ceiling";
      break;
    case Kind::kWood:
      img = make_wood_texture(size, t, r, false), name = "wood";
      break;
    case Kind::kDesk:
      img = make_wood_texture(size, t, r, true), name = "desk";
      break;
    case Kind::kShelf:
      img = make_bookshelf_texture(size, t, r), name = "bookshelf";
      break;
    case Kind::kCardboard:
      img = make_cardboard_texture(size, t, r), name = "cardboard";
      break;
  }
  return scene.add_texture(make_texture(img, {}, "procedural:" + name));
}

/// A box whose five faces get their own procedural textures of `kind` (top: `top_kind`).
void add_textured_box(Scene& scene, const Vec3d& bottom_centre, const Vec3d& size, double yaw,
                      Kind kind, Kind top_kind, double texel_m, Rng& rng) {
  std::vector<int> sides;
  for (int i = 0; i < 4; ++i) {
    const double w = (i % 2 == 0) ? size.y() : size.x();
    sides.push_back(add_procedural(scene, kind, w, size.z(), texel_m, rng));
  }
  const int top = add_procedural(scene, top_kind, size.x(), size.y(), texel_m, rng);
  for (auto& s : make_box(bottom_centre, size, yaw, sides, top)) scene.surfaces.push_back(s);
}

/// A poster on a wall: a photo when one is available, else a procedural poster. Placed 5 mm in
/// front of the wall so it never z-fights with it.
void add_poster(Scene& scene, const Vec3d& centre, const Vec3d& normal, double height_m,
                const std::vector<std::string>& photos, std::size_t& next_photo, Rng& rng) {
  cv::Mat img;
  std::string source;
  while (img.empty() && next_photo < photos.size()) {
    source = photos[next_photo++];
    img = cv::imread(source, cv::IMREAD_COLOR);
    if (img.empty()) spdlog::debug("synthetic: poster photo {} not readable, skipped", source);
  }
  if (img.empty()) {
    Rng r = rng.fork(0x9051e5 + scene.textures.size());
    img = make_poster_texture(cv::Size(420, 594), r);
    source = "procedural:poster";
  } else if (std::max(img.cols, img.rows) > 1024) {
    const double s = 1024.0 / std::max(img.cols, img.rows);
    cv::resize(img, img, cv::Size(), s, s, cv::INTER_AREA);
  }
  const double width_m = height_m * img.cols / img.rows;
  const int tex = scene.add_texture(make_texture(img, {}, source));
  scene.surfaces.push_back(
      make_rect(centre + 0.005 * normal, normal, Vec3d::UnitZ(), width_m, height_m, tex));
}

}  // namespace

float plane_shade(const Vec3d& front_normal_w) {
  const Vec3d light = Vec3d(0.35, -0.25, 0.9).normalized();
  const Vec3d fill = Vec3d(-0.6, 0.7, 0.2).normalized();
  const double d = std::max(0.0, front_normal_w.dot(light));
  const double f = std::max(0.0, front_normal_w.dot(fill));
  return static_cast<float>(0.58 + 0.34 * d + 0.12 * f);
}

Surface make_rect(const Vec3d& centre_w, const Vec3d& normal_w, const Vec3d& up_w, double width_m,
                  double height_m, int texture, int entity) {
  const Vec3d n = normal_w.normalized();
  const Vec3d up = (up_w - up_w.dot(n) * n).normalized();
  const Vec3d right = (-n).cross(up);  // a viewer looking along -n sees `right` to the right
  Surface s;
  s.origin_w = centre_w - right * (width_m / 2) + up * (height_m / 2);
  s.u_w = right * width_m;
  s.v_w = -up * height_m;
  s.texture = texture;
  s.entity = entity;
  s.shade = plane_shade(n);
  return s;
}

std::vector<Surface> make_box(const Vec3d& bottom_centre_w, const Vec3d& size_m, double yaw_rad,
                              const std::vector<int>& side_textures, int top_texture, int entity) {
  const Vec3d ax(std::cos(yaw_rad), std::sin(yaw_rad), 0.0);
  const Vec3d ay(-std::sin(yaw_rad), std::cos(yaw_rad), 0.0);
  const Vec3d mid = bottom_centre_w + Vec3d(0, 0, size_m.z() / 2);
  std::vector<Surface> out;
  const Vec3d normals[4] = {ax, ay, -ax, -ay};
  const double half_depth[4] = {size_m.x() / 2, size_m.y() / 2, size_m.x() / 2, size_m.y() / 2};
  const double widths[4] = {size_m.y(), size_m.x(), size_m.y(), size_m.x()};
  for (int i = 0; i < 4; ++i) {
    out.push_back(make_rect(mid + normals[i] * half_depth[i], normals[i], Vec3d::UnitZ(), widths[i],
                            size_m.z(), side_textures[static_cast<std::size_t>(i)], entity));
  }
  out.push_back(make_rect(bottom_centre_w + Vec3d(0, 0, size_m.z()), Vec3d::UnitZ(), ay, size_m.x(),
                          size_m.y(), top_texture, entity));
  return out;
}

int Scene::add_texture(Texture texture) {
  textures.push_back(std::move(texture));
  return static_cast<int>(textures.size()) - 1;
}

Scene build_room(const RoomOptions& options, const RoomLayout& layout, Rng& rng) {
  Scene scene;
  const double W = scene.room_max.x();
  const double D = scene.room_max.y();
  const double H = scene.room_max.z();
  const double tx = options.texel_m;
  // Walls (front normals point into the room), floor and ceiling.
  struct WallSpec {
    Vec3d centre, normal;
    double width;
  };
  const WallSpec walls[4] = {{{W / 2, D, H / 2}, {0, -1, 0}, W},
                             {{W / 2, 0, H / 2}, {0, 1, 0}, W},
                             {{W, D / 2, H / 2}, {-1, 0, 0}, D},
                             {{0, D / 2, H / 2}, {1, 0, 0}, D}};
  for (const auto& w : walls) {
    const int tex = add_procedural(scene, Kind::kWall, w.width, H, tx, rng);
    scene.surfaces.push_back(make_rect(w.centre, w.normal, Vec3d::UnitZ(), w.width, H, tex));
  }
  scene.surfaces.push_back(make_rect({W / 2, D / 2, 0}, Vec3d::UnitZ(), Vec3d::UnitY(), W, D,
                                     add_procedural(scene, Kind::kFloor, W, D, tx, rng)));
  scene.surfaces.push_back(make_rect({W / 2, D / 2, H}, -Vec3d::UnitZ(), Vec3d::UnitY(), W, D,
                                     add_procedural(scene, Kind::kCeiling, W, D, 0.004, rng)));

  const double furniture_texel = 0.0025;
  // The desk (solid, so seated people are hidden below its top).
  const Vec3d desk_size = layout.desk_max - layout.desk_min;
  const Vec3d desk_centre((layout.desk_min.x() + layout.desk_max.x()) / 2,
                          (layout.desk_min.y() + layout.desk_max.y()) / 2, 0);
  add_textured_box(scene, desk_centre, desk_size, 0.0, Kind::kWood, Kind::kDesk, furniture_texel,
                   rng);
  // Bookshelves against the far wall, left and right of the desk.
  for (double x : {1.15, 4.85}) {
    const Vec3d size(1.5, 0.35, 1.9);
    std::vector<int> sides;
    sides.push_back(add_procedural(scene, Kind::kWood, size.y(), size.z(), furniture_texel, rng));
    sides.push_back(add_procedural(scene, Kind::kWood, size.x(), size.z(), furniture_texel, rng));
    sides.push_back(add_procedural(scene, Kind::kWood, size.y(), size.z(), furniture_texel, rng));
    sides.push_back(add_procedural(scene, Kind::kShelf, size.x(), size.z(), 0.002, rng));
    const int top = add_procedural(scene, Kind::kWood, size.x(), size.y(), furniture_texel, rng);
    for (auto& s : make_box({x, D - size.y() / 2, 0}, size, 0.0, sides, top)) {
      scene.surfaces.push_back(s);
    }
  }
  // Side table (top slab on legs) along the west wall, with boxes on it.
  {
    const Vec3d top_size(0.7, 1.8, 0.04);
    add_textured_box(scene, {0.36, 2.5, 0.71}, top_size, 0.0, Kind::kWood, Kind::kDesk,
                     furniture_texel, rng);
    for (double lx : {0.06, 0.64}) {
      for (double ly : {1.66, 3.34}) {
        add_textured_box(scene, {lx, ly, 0}, {0.05, 0.05, 0.71}, 0.0, Kind::kWood, Kind::kWood,
                         furniture_texel, rng);
      }
    }
    add_textured_box(scene, {0.35, 2.0, 0.75}, {0.4, 0.3, 0.28}, 0.1, Kind::kCardboard,
                     Kind::kCardboard, 0.002, rng);
    add_textured_box(scene, {0.3, 3.0, 0.75}, {0.3, 0.45, 0.22}, -0.2, Kind::kCardboard,
                     Kind::kCardboard, 0.002, rng);
  }
  // Cabinet along the east wall with a box on top.
  add_textured_box(scene, {5.75, 1.8, 0}, {0.5, 1.6, 1.1}, 0.0, Kind::kWood, Kind::kDesk,
                   furniture_texel, rng);
  add_textured_box(scene, {5.7, 1.5, 1.1}, {0.35, 0.5, 0.3}, 0.15, Kind::kCardboard,
                   Kind::kCardboard, 0.002, rng);
  // Boxes on the floor.
  add_textured_box(scene, {5.3, 4.0, 0}, {0.5, 0.45, 0.45}, 0.3, Kind::kCardboard, Kind::kCardboard,
                   0.002, rng);
  add_textured_box(scene, {0.8, 0.6, 0}, {0.6, 0.5, 0.5}, -0.25, Kind::kCardboard, Kind::kCardboard,
                   0.002, rng);
  add_textured_box(scene, {1.9, 4.3, 0}, {0.45, 0.4, 0.35}, 0.5, Kind::kCardboard, Kind::kCardboard,
                   0.002, rng);
  // Posters: photos first (when given), then procedural ones.
  std::size_t next_photo = 0;
  add_poster(scene, {3.0, D, 1.75}, {0, -1, 0}, 0.8, options.poster_images, next_photo, rng);
  add_poster(scene, {1.5, 0, 1.6}, {0, 1, 0}, 0.9, options.poster_images, next_photo, rng);
  add_poster(scene, {4.4, 0, 1.5}, {0, 1, 0}, 0.7, options.poster_images, next_photo, rng);
  add_poster(scene, {0, 1.2, 1.6}, {1, 0, 0}, 0.8, options.poster_images, next_photo, rng);
  add_poster(scene, {0, 4.0, 1.5}, {1, 0, 0}, 0.7, options.poster_images, next_photo, rng);
  add_poster(scene, {W, 3.6, 1.6}, {-1, 0, 0}, 0.9, options.poster_images, next_photo, rng);
  add_poster(scene, {W, 0.5, 1.7}, {-1, 0, 0}, 0.6, options.poster_images, next_photo, rng);
  return scene;
}

}  // namespace ddl::synthetic
