#pragma once
// Shared by the test suites: where the real data is. Include as "shared_data.h"
// (cmake/DdlModule.cmake puts tests/common on every test's include path).

#include <cstdlib>
#include <string>

namespace ddl::test_support {

/// The shared data folder: $DDL_SHARED_DIR when set, else ../shared beside the source tree.
inline std::string shared_dir() {
  if (const char* env = std::getenv("DDL_SHARED_DIR"); env != nullptr && *env != '\0') return env;
  return DDL_DEFAULT_SHARED_DIR;
}

/// Debian opencv-doc's photo of two basketball players (640x480).
inline constexpr char kBasketballPhoto[] =
    "/usr/share/doc/opencv-doc/examples/data/basketball1.png";

}  // namespace ddl::test_support
