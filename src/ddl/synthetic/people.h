#pragma once
// People as upright cut-out billboards. A person is a photo with a pixel mask (CCP dataset layout:
// <dir>/images/NNNN.jpg + <dir>/masks/NNNN.png, 255 = person) cropped to the mask's bounding box,
// or a procedural coloured silhouette when no photos are available. The billboard stands on the
// floor (its bottom edge at the feet), is upright (world z), and turns about the vertical axis to
// face the camera centre in every frame, so the camera always sees the person's front as in the
// photo. Only pixels with >= 50% mask coverage exist (the renderer's alpha test), so the dynamic
// mask is exactly the person's silhouette.
//
// Tracks (positions on the floor over time, all smooth):
//   walking    back and forth between two floor points with a cosine speed profile (stops and
//              turns at the ends, about 1 m/s in the middle), a small side-to-side wander and a
//              vertical bob at the step frequency
//   sitting    seated behind a desk: the billboard shows the upper 58% of the person (head to
//              hips), placed at seated height; the upper part sways (head and arms) and the whole
//              body shifts and turns slightly
//   appearing  invisible until `appear_s`, then walks from `a` to `b` in `walk_s` seconds and
//              stands there moving little (small sway and shift)

#include <cstdint>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "ddl/core/types.h"
#include "ddl/synthetic/random.h"
#include "ddl/synthetic/scene.h"

namespace ddl::synthetic {

struct PersonAppearance {
  int texture = -1;          // full-body texture (with alpha) in the scene
  int sitting_texture = -1;  // upper-body crop for seated people
  double aspect = 0.4;       // width / height of the full-body crop
  double sitting_aspect = 0.7;
  std::string source;  // photo path or "procedural:silhouette"
};

/// Lists the usable photos of a CCP-layout folder (images/*.jpg with a masks/*.png of the same
/// stem), sorted by name. Empty when the folder is absent.
std::vector<std::string> list_person_photos(const std::string& people_dir);

/// Adds `count` people to the scene's textures: photos picked from `people_dir` by `rng` (without
/// repeats while possible) or silhouettes when the folder has none. Throws ddl::InputError naming
/// the file when a listed photo or mask cannot be decoded.
std::vector<PersonAppearance> load_people(Scene& scene, const std::string& people_dir, int count,
                                          Rng& rng);

enum class PersonTrackType { kWalking, kSitting, kAppearing };

struct PersonTrack {
  PersonTrackType type = PersonTrackType::kWalking;
  int appearance = 0;         // index into the appearances
  double height_m = 1.75;     // standing height (1.6-1.9 m)
  Vec3d a_w = Vec3d::Zero();  // walking: one end; sitting: seat (floor point); appearing: start
  Vec3d b_w = Vec3d::Zero();  // walking: other end; appearing: where the person stops
  double period_s = 8.0;      // walking: time for a there-and-back
  double phase = 0.0;         // walking: phase in radians
  double appear_s = 0.0;      // appearing: time the person enters
  double walk_s = 3.0;        // appearing: time to walk from a to b
  std::uint64_t seed = 0;     // small motions
};

struct PersonState {
  bool visible = false;
  Vec3d foot_w = Vec3d::Zero();  // billboard bottom centre on the floor (or seat height)
  double height_m = 0.0;         // billboard height
  double sway = 0.0;             // texture-space sway of the upper part
};

PersonState person_state(const PersonTrack& track, double t_s);

/// The billboard of a person at `state`, facing the camera at `camera_w`, as a surface of entity
/// `entity`.
Surface person_billboard(const PersonTrack& track, const PersonAppearance& appearance,
                         const PersonState& state, const Vec3d& camera_w, int entity);

}  // namespace ddl::synthetic
