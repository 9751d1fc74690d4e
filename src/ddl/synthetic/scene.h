#pragma once
// Scene description for the synthetic renderer: textured rectangles ("surfaces") in the world
// frame. World frame of the synthetic rooms: x east, y north, z up, metres; the floor is z = 0 and
// the room spans [0, width] x [0, depth] x [0, height].
//
// A surface is a rectangle with a texture mapped onto it: `origin_w` is the world position of the
// texture's top-left corner, `u_w` the edge along the texture's columns (left to right) and `v_w`
// the edge along its rows (top to bottom); u and v are perpendicular. Seen from the front, u points
// right and v down, so the front normal is v x u. Surfaces are two-sided for visibility.

#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "ddl/core/types.h"
#include "ddl/synthetic/random.h"
#include "ddl/synthetic/texture.h"

namespace ddl::synthetic {

struct Surface {
  Vec3d origin_w = Vec3d::Zero();  // world position of the texture's top-left corner, metres
  Vec3d u_w = Vec3d::UnitX();      // edge vector along texture columns, metres
  Vec3d v_w = -Vec3d::UnitZ();     // edge vector along texture rows, metres (perpendicular to u)
  int texture = 0;                 // index into Scene::textures
  cv::Vec4f tex_rect{0, 0, 1, 1};  // sub-window of the texture: s0, t0, s1, t1 in [0, 1]
  float shade = 1.0f;              // lighting factor applied to the texture colour
  int entity = 0;                  // 0: static scene; k > 0: movable entity k (person, object)
  float sway = 0.0f;  // texture-space shear of the upper part: s += sway * max(0, 1 - t/0.5)^2
                      // (t = texture row in [0, 1]); animates seated people's head and arms
  Vec3d front_normal() const { return v_w.cross(u_w).normalized(); }
};

/// Lighting factor of a surface with the given front normal: ambient plus a diffuse term from a
/// fixed ceiling-light direction. Per plane, as a simple plausible shading.
float plane_shade(const Vec3d& front_normal_w);

/// Appends the rectangle with centre `centre_w`, front normal `normal_w` (towards the viewer),
/// `up_w` (projected into the plane; the texture's top points along it), width and height in
/// metres. Shade comes from plane_shade(). Returns the new surface.
Surface make_rect(const Vec3d& centre_w, const Vec3d& normal_w, const Vec3d& up_w, double width_m,
                  double height_m, int texture, int entity = 0);

/// A box resting on z = bottom_z: five faces (no bottom), outward normals, centred at
/// (centre_xy, bottom_z), sizes along its own x/y axes rotated by yaw about z. `side_textures`
/// holds 4 side textures (+x, +y, -x, -y faces) and `top_texture` the top.
std::vector<Surface> make_box(const Vec3d& bottom_centre_w, const Vec3d& size_m, double yaw_rad,
                              const std::vector<int>& side_textures, int top_texture,
                              int entity = 0);

struct Scene {
  std::vector<Texture> textures;
  std::vector<Surface> surfaces;  // static surfaces
  Vec3d room_min = Vec3d::Zero();
  Vec3d room_max = Vec3d(6.0, 5.0, 2.7);
  /// Adds a texture and returns its index.
  int add_texture(Texture texture);
};

/// Where things are in the standard room (used by the people, the movable object and the cameras).
struct RoomLayout {
  Vec3d desk_min = Vec3d(2.2, 3.4, 0.0);  // solid desk in the middle of the far half
  Vec3d desk_max = Vec3d(3.8, 4.2, 0.75);
  Vec3d view_position_w = Vec3d(3.0, 1.1, 1.45);  // the cameras' base viewpoint
  Vec3d view_target_w = Vec3d(3.0, 4.2, 0.95);    // what they look at
};

struct RoomOptions {
  double texel_m = 0.0035;  // metric size of a texel of the large procedural textures
  std::vector<std::string> poster_images;  // photos used as posters (missing files are skipped)
};

/// Builds the room of RoomLayout (walls, floor, ceiling, desk, side table, cabinet, bookshelves,
/// boxes, posters) with textures drawn from `rng`. Poster photos that cannot be read are replaced
/// by procedural posters (logged at debug level). Deterministic for a given rng state and options.
Scene build_room(const RoomOptions& options, const RoomLayout& layout, Rng& rng);

}  // namespace ddl::synthetic
