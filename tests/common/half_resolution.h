#pragma once
// Shared by the test suites: a camera at half the resolution with the same field of view, for
// fast renders of the synthetic presets. Include as "half_resolution.h" (cmake/DdlModule.cmake
// puts tests/common on every test's include path).

#include "ddl/camera/pinhole_camera.h"

namespace ddl::test_support {

/// `c` at half its width and height: focal lengths halved, principal point moved so that pixel
/// centres correspond exactly ((x + 0.5) / 2 - 0.5).
inline camera::PinholeCamera half_resolution(camera::PinholeCamera c) {
  c.width /= 2;
  c.height /= 2;
  c.fx /= 2;
  c.fy /= 2;
  c.cx = (c.cx + 0.5) / 2 - 0.5;
  c.cy = (c.cy + 0.5) / 2 - 0.5;
  return c;
}

}  // namespace ddl::test_support
