#pragma once
// Test fixture: a textured box room with two boxes inside, ray-cast exactly for any camera pose,
// so tracking tests know the true pose and depth of every pixel. Textures are random blobs,
// rectangles and speckle (corners at many scales for ORB), fixed by the seed.
//
// World frame: x right, y down (floor at y = +1.2 m), z forward; the room spans
// x in [-2, 2], y in [-1.2, 1.2], z in [-1.5, 2.5] metres.

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"
#include "ddl/io/rgbd_frame.h"

namespace ddl::tracking::testing {

class SyntheticRoom {
 public:
  explicit SyntheticRoom(std::uint64_t seed = 7);

  /// Colour (BGR, grey texture) and exact depth (metres along the optical axis) seen from
  /// T_w_c. Pixel noise of `noise_sigma` grey levels (seeded by `index`) when > 0.
  io::RgbdFrame render(const camera::PinholeCamera& camera, const SE3& T_w_c, std::size_t index,
                       double timestamp_s, double noise_sigma = 0.0) const;

 private:
  struct Face {
    int axis;         // 0 = x, 1 = y, 2 = z: the face's normal axis
    double position;  // coordinate of the plane along `axis`
    int u_axis;       // in-plane axes used as texture coordinates
    int v_axis;
    double u0, v0;    // texture origin (metres)
    cv::Mat texture;  // CV_32F grey, kTexelsPerMetre
  };
  struct Box {
    Vec3d min;
    Vec3d max;
    int first_face;  // index of its 6 faces in faces_ (-x, +x, -y, +y, -z, +z)
  };
  int add_face(int axis, double position, double u_extent_m, double v_extent_m, double u0,
               double v0, cv::RNG& rng);
  float shade(const Face& face, const Vec3d& p) const;

  Vec3d room_min_{-2.0, -1.2, -1.5};
  Vec3d room_max_{2.0, 1.2, 2.5};
  std::vector<Face> faces_;
  int room_first_face_ = 0;
  std::vector<Box> boxes_;
};

/// A smooth hand-held-like trajectory of `frames` poses around the room's centre looking at +z:
/// translation up to ~15 cm and rotation up to ~6 degrees, T_w_c per frame.
std::vector<SE3> smooth_trajectory(int frames);

}  // namespace ddl::tracking::testing
