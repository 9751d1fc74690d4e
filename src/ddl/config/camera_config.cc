#include "ddl/config/camera_config.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <cstdlib>
#include <filesystem>

#include "ddl/config/builtin_cameras.h"
#include "ddl/core/error.h"

namespace ddl::config {
namespace fs = std::filesystem;

namespace {

// Names in the YAML schema, in the order camera_to_yaml writes them.
constexpr std::string_view kCameraSection = "camera";

std::string quote(const std::string& text) {
  std::string out = "\"";
  for (char c : text) {
    if (c == '\n') {
      out += "\\n";
      continue;
    }
    if (c == '"' || c == '\\') out.push_back('\\');
    out.push_back(c);
  }
  out.push_back('"');
  return out;
}

camera::PinholeCamera parse_and_validate(const YamlFile& file, const std::string& default_name) {
  const YamlMap section = file.root().get_map(std::string(kCameraSection));
  camera::PinholeCamera camera = read_camera(section, default_name);
  file.check_all_keys_used();
  try {
    camera.validate();
  } catch (const ConfigError& e) {
    // validate() names the key; add the file, and the key's line, so the user knows what to fix.
    const std::string key = e.key();
    const std::string prefix = std::string(kCameraSection) + ".";
    const int line = key.rfind(prefix, 0) == 0 ? section.line_of(key.substr(prefix.size())) : 0;
    throw ConfigError(line > 0 ? fmt::format("{}:{}: {}", file.source(), line, e.what())
                               : fmt::format("{}: {}", file.source(), e.what()));
  }
  return camera;
}

std::string stem_of(const std::string& path) { return fs::path(path).stem().string(); }

}  // namespace

std::vector<std::string> builtin_camera_names() {
  std::vector<std::string> names;
  for (const detail::EmbeddedFile& f : detail::embedded_cameras()) names.emplace_back(f.name);
  return names;
}

bool is_builtin_camera(const std::string& name) {
  for (const detail::EmbeddedFile& f : detail::embedded_cameras()) {
    if (f.name == name) return true;
  }
  return false;
}

std::string_view embedded_camera_yaml(const std::string& name) {
  for (const detail::EmbeddedFile& f : detail::embedded_cameras()) {
    if (f.name == name) return f.text;
  }
  throw ConfigError::for_key("camera", fmt::format("'{}' is not a builtin camera", name));
}

std::string builtin_camera_source(const std::string& name) {
  if (!is_builtin_camera(name)) {
    throw ConfigError::for_key("camera", fmt::format("'{}' is not a builtin camera", name));
  }
  const std::string file_name = name + ".yaml";
  std::error_code ec;
  if (const char* override_dir = std::getenv("DDL_CONFIG_DIR");
      override_dir != nullptr && *override_dir != '\0') {
    const fs::path path = fs::path(override_dir) / "cameras" / file_name;
    if (!fs::is_regular_file(path, ec)) {
      throw InputError::at(path.string(),
                           fmt::format("builtin camera '{}' not found there (DDL_CONFIG_DIR is "
                                       "set to '{}'; unset it to use the built-in copy)",
                                       name, override_dir));
    }
    return path.string();
  }
  const fs::path source_path = fs::path(DDL_SOURCE_CONFIG_DIR) / "cameras" / file_name;
  if (fs::is_regular_file(source_path, ec)) return source_path.string();
  return "<embedded>/" + file_name;
}

camera::PinholeCamera read_camera(const YamlMap& map, const std::string& default_name) {
  camera::PinholeCamera camera;
  camera.name = default_name;
  map.read("name", camera.name);
  camera.width = map.get_int("width");
  camera.height = map.get_int("height");
  camera.fx = map.get_double("fx");
  camera.fy = map.get_double("fy");
  camera.cx = map.get_double("cx");
  camera.cy = map.get_double("cy");
  camera.distortion = {0, 0, 0, 0, 0};
  map.read("distortion", camera.distortion);
  camera.depth_factor = map.get_double("depth_factor");
  map.read("fps", camera.fps);
  if (map.has("depth_time_offset_s"))
    camera.depth_time_offset_s = map.get_double("depth_time_offset_s");
  if (camera.name.empty()) map.fail("name", "must not be empty");
  return camera;
}

camera::PinholeCamera parse_camera(const std::string& yaml_text, const std::string& source_name) {
  return parse_and_validate(YamlFile::parse(yaml_text, source_name), stem_of(source_name));
}

camera::PinholeCamera load_camera(const std::string& path_or_builtin) {
  if (is_builtin_camera(path_or_builtin)) {
    const std::string source = builtin_camera_source(path_or_builtin);
    camera::PinholeCamera camera =
        source.rfind("<embedded>", 0) == 0
            ? parse_camera(std::string(embedded_camera_yaml(path_or_builtin)), source)
            : parse_and_validate(YamlFile::load(source), path_or_builtin);
    spdlog::debug("camera '{}' from {}", camera.name, source);
    return camera;
  }
  std::error_code ec;
  if (!fs::exists(path_or_builtin, ec)) {
    std::string names;
    for (const std::string& n : builtin_camera_names()) names += (names.empty() ? "" : "|") + n;
    throw InputError::at(
        path_or_builtin,
        fmt::format("camera file not found (and not a builtin camera: {})", names));
  }
  return parse_and_validate(YamlFile::load(path_or_builtin), stem_of(path_or_builtin));
}

std::string camera_to_yaml(const camera::PinholeCamera& c) {
  // fmt's "{}" for double is the shortest text that reads back to the same value.
  const auto& d = c.distortion;
  return fmt::format(
      "camera:\n"
      "  name: {}\n"
      "  width: {}\n"
      "  height: {}\n"
      "  fx: {}\n"
      "  fy: {}\n"
      "  cx: {}\n"
      "  cy: {}\n"
      "  distortion: [{}, {}, {}, {}, {}]  # k1 k2 p1 p2 k3\n"
      "  depth_factor: {}\n"
      "  fps: {}\n{}",
      quote(c.name), c.width, c.height, c.fx, c.fy, c.cx, c.cy, d[0], d[1], d[2], d[3], d[4],
      c.depth_factor, c.fps,
      c.depth_time_offset_s ? fmt::format("  depth_time_offset_s: {}\n", *c.depth_time_offset_s)
                            : std::string());
}

}  // namespace ddl::config
