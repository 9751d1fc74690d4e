#pragma once
// Internal: the builtin camera files embedded at build time (generated builtin_cameras.cc from
// config/cameras/*.yaml, see CMakeLists.txt). Use camera_config.h instead.

#include <span>
#include <string_view>

namespace ddl::config::detail {

struct EmbeddedFile {
  std::string_view name;  // builtin name, e.g. "tum1"
  std::string_view text;  // the file's content as it was at build time
};

std::span<const EmbeddedFile> embedded_cameras();

}  // namespace ddl::config::detail
