#pragma once
// Test helpers: a throw-away folder with a tiny TUM-layout sequence written with OpenCV, and the
// location of the shared data.

#include <gtest/gtest.h>
#include <unistd.h>

#include <atomic>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <string>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "shared_data.h"

namespace ddl::test {

/// $DDL_SHARED_DIR, else the build's default ../shared.
inline std::string shared_dir() { return test_support::shared_dir(); }

/// A unique empty folder under the system temp dir, removed on destruction.
class TempDir {
 public:
  explicit TempDir(const std::string& name) {
    static std::atomic<int> counter{0};
    path_ = std::filesystem::temp_directory_path() /
            ("ddl_test_" + std::to_string(::getpid()) + "_" + std::to_string(counter++)) / name;
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_.parent_path(), ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string path() const { return path_.string(); }
  std::string file(const std::string& relative) const { return (path_ / relative).string(); }
  void write(const std::string& relative, const std::string& text) const {
    const std::filesystem::path p = path_ / relative;
    std::filesystem::create_directories(p.parent_path());
    std::ofstream(p, std::ios::binary) << text;
  }

 private:
  std::filesystem::path path_;
};

/// A small undistorted camera for crafted sequences.
inline camera::PinholeCamera tiny_camera(int width = 32, int height = 24) {
  camera::PinholeCamera c;
  c.name = "tiny";
  c.width = width;
  c.height = height;
  c.fx = c.fy = 30.0;
  c.cx = (width - 1) / 2.0;
  c.cy = (height - 1) / 2.0;
  c.depth_factor = 5000.0;
  return c;
}

/// Writes a TUM-layout sequence of `n` frames at 30 Hz into `dir`: rgb/<t>.png (8-bit BGR) and
/// depth/<t>.png (16-bit, raw value 5000 + 10 * column), rgb.txt, depth.txt. Depth stamps lag
/// RGB by 3 ms. Returns the RGB stamps (as written).
inline std::vector<std::string> write_sequence(const TempDir& dir, int n, int width = 32,
                                               int height = 24) {
  std::vector<std::string> rgb_stamps;
  std::string rgb_list = "# color images\n# timestamp filename\n";
  std::string depth_list = "# depth maps\n# timestamp filename\n";
  std::filesystem::create_directories(dir.file("rgb"));
  std::filesystem::create_directories(dir.file("depth"));
  for (int i = 0; i < n; ++i) {
    const std::string t_rgb = cv::format("%.6f", 1000.0 + i / 30.0);
    const std::string t_depth = cv::format("%.6f", 1000.003 + i / 30.0);
    cv::Mat rgb(height, width, CV_8UC3, cv::Scalar(10 * i % 256, 100, 200));
    cv::Mat depth(height, width, CV_16UC1);
    for (int v = 0; v < height; ++v) {
      for (int u = 0; u < width; ++u)
        depth.at<uint16_t>(v, u) = static_cast<uint16_t>(5000 + 10 * u);
    }
    cv::imwrite(dir.file("rgb/" + t_rgb + ".png"), rgb);
    cv::imwrite(dir.file("depth/" + t_depth + ".png"), depth);
    rgb_list += t_rgb + " rgb/" + t_rgb + ".png\n";
    depth_list += t_depth + " depth/" + t_depth + ".png\n";
    rgb_stamps.push_back(t_rgb);
  }
  dir.write("rgb.txt", rgb_list);
  dir.write("depth.txt", depth_list);
  return rgb_stamps;
}

}  // namespace ddl::test
