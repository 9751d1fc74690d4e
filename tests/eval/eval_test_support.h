#pragma once
// Helpers shared by the eval tests: the shared data folder, temporary folders and small files.

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <string>

#include "ddl/core/se3.h"
#include "ddl/io/trajectory_io.h"
#include "shared_data.h"

namespace ddl::eval::test {

/// $DDL_SHARED_DIR if set, else the build's default ../shared.
inline std::filesystem::path shared_dir() { return test_support::shared_dir(); }

inline std::filesystem::path reference_groundtruth() {
  return shared_dir() / "data/tum/rgbd_dataset_freiburg1_rpy/groundtruth.txt";
}
inline std::filesystem::path reference_estimate() {
  return shared_dir() / "reference/eval/fr1_rpy_orbslam2_run1.txt";
}
inline std::filesystem::path reference_expected_json() {
  return shared_dir() / "reference/eval/fr1_rpy_orbslam2_run1.expected.json";
}
inline std::filesystem::path reference_associations() {
  return shared_dir() / "data/tum/rgbd_dataset_freiburg1_rpy/associations.txt";
}

/// A fresh empty folder under the system temp dir, removed by the destructor.
class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_(std::filesystem::temp_directory_path() /
              ("ddl_eval_" + name + "_" + std::to_string(::getpid()))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  const std::filesystem::path& path() const { return path_; }
  std::string file(const std::string& name) const { return (path_ / name).string(); }

 private:
  std::filesystem::path path_;
};

inline std::string write_text(const std::string& path, const std::string& text) {
  std::ofstream(path, std::ios::trunc) << text;
  return path;
}

inline std::string read_text(const std::string& path) {
  std::ifstream file(path);
  return std::string(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
}

}  // namespace ddl::eval::test
