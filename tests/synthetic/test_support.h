#pragma once
// Helpers shared by the synthetic tests.

#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <string>

#include "ddl/synthetic/sequence.h"
#include "half_resolution.h"
#include "shared_data.h"

namespace ddl::synthetic::testing {

inline std::string shared_dir() { return test_support::shared_dir(); }

/// A preset at 320x240 (intrinsics halved), with the shared people photos when present.
inline SequenceConfig small_config(const std::string& preset, int frames) {
  SequenceConfig c = find_preset(preset).config;
  c.frames = frames;
  c.camera = test_support::half_resolution(c.camera);
  c.people_dir = shared_dir() + "/data/people/ccp";
  return c;
}

/// A fresh empty temporary folder, removed by the destructor.
class TempDir {
 public:
  explicit TempDir(const std::string& name)
      : path_(std::filesystem::temp_directory_path() /
              (name + "_" + std::to_string(static_cast<long long>(::getpid())))) {
    std::filesystem::remove_all(path_);
    std::filesystem::create_directories(path_);
  }
  ~TempDir() {
    std::error_code ec;
    std::filesystem::remove_all(path_, ec);
  }
  TempDir(const TempDir&) = delete;
  TempDir& operator=(const TempDir&) = delete;
  std::string str() const { return path_.string(); }
  std::filesystem::path path() const { return path_; }

 private:
  std::filesystem::path path_;
};

}  // namespace ddl::synthetic::testing
