#pragma once
// Test images for the features tests: the real TUM fr1_rpy frames when ../shared is present, and a
// synthetic textured image that needs no data.

#include <cstdint>
#include <filesystem>
#include <opencv2/core.hpp>
#include <string>

namespace ddl::features::test {

/// $DDL_SHARED_DIR if set, else the build's default ../shared.
std::filesystem::path shared_dir();

/// Folder of the fr1_rpy sequence inside shared_dir().
std::filesystem::path tum_rpy_dir();

/// Grayscale frame `index` (0-based, in rgb.txt order) of fr1_rpy, or an empty Mat when the
/// sequence is absent. `path_out`, if given, receives the file that was (or would be) read.
cv::Mat load_tum_rpy_gray(int index, std::string* path_out = nullptr);

/// A deterministic textured grayscale image: random filled rectangles, ellipses, triangles and
/// lines of random grey levels and sizes (4..90 px) on a grey background, lightly smoothed. Rich
/// in corners at every pyramid scale.
cv::Mat make_textured_image(cv::Size size, std::uint64_t seed = 1);

/// Keeps the GTEST_SKIP message in one place.
#define DDL_SKIP_WITHOUT_TUM(image, path)                                               \
  if ((image).empty()) {                                                                \
    GTEST_SKIP() << "fr1_rpy frame not found: " << (path)                               \
                 << " (set DDL_SHARED_DIR to the shared data folder to run this test)"; \
  }

}  // namespace ddl::features::test
