#pragma once
// Camera files (YAML). Schema, flat keys under `camera:` (docs/configuration.md):
//
//   camera:
//     name: tum1                  # optional, default: the file name without extension
//     width: 640                  # required, pixels
//     height: 480                 # required, pixels
//     fx: 517.306408              # required, focal lengths and principal point in pixels
//     fy: 516.469215
//     cx: 318.643040
//     cy: 255.313989
//     distortion: [0.262383, -0.953104, -0.005358, 0.002628, 1.163314]  # k1 k2 p1 p2 k3,
//                                 # optional, default no distortion
//     depth_factor: 5000.0        # required, raw depth units per metre
//     fps: 30.0                   # optional, default 30
//     depth_time_offset_s: -0.020 # optional: the depth image was captured at its stamp plus
//                                 # this (seconds); absent: with its colour image (synchronised)
//
// Builtin cameras tum1, tum2, tum3, bonn, synthetic are the files config/cameras/<name>.yaml of
// the repository. They are found, in this order:
//   1. $DDL_CONFIG_DIR/cameras/<name>.yaml when the environment variable DDL_CONFIG_DIR is set
//      (it must then hold the file: an explicit override never falls back silently);
//   2. <source tree>/config/cameras/<name>.yaml (compile-time path), when that file exists;
//   3. a copy of the same file embedded in the library at build time, so an installed binary
//      works anywhere.
//
// Threads: free functions without shared state; callable from any thread (they read the
// environment and files).

#include <string>
#include <string_view>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/config/yaml_reader.h"

namespace ddl::config {

/// Names accepted by load_camera() besides file paths.
std::vector<std::string> builtin_camera_names();
bool is_builtin_camera(const std::string& name);

/// Loads and validates a camera from a YAML file path or a builtin name. Throws ddl::InputError
/// (file missing/unreadable, neither a file nor a builtin) or ddl::ConfigError (syntax error,
/// unknown/missing key, wrong type, invalid value), every message naming the file and key.
camera::PinholeCamera load_camera(const std::string& path_or_builtin);

/// Parses camera YAML text; `source_name` names it in messages. Validates.
camera::PinholeCamera parse_camera(const std::string& yaml_text, const std::string& source_name);

/// Reads the keys of a `camera:` map into a camera; `default_name` is used when `name` is absent.
/// Does not validate and does not check for unknown keys (the owner of the YamlFile does), so a
/// larger configuration file can embed a camera section.
camera::PinholeCamera read_camera(const YamlMap& camera_map, const std::string& default_name);

/// The effective camera as YAML (same schema; numbers in shortest round-trip form), for writing
/// next to run outputs. parse_camera(camera_to_yaml(c), ...) reproduces c exactly.
std::string camera_to_yaml(const camera::PinholeCamera& camera);

/// Where builtin `name` is read from: a file path (cases 1 and 2 above) or "<embedded>/name.yaml".
std::string builtin_camera_source(const std::string& name);
/// The YAML text of builtin `name` as compiled into the library (case 3 above).
std::string_view embedded_camera_yaml(const std::string& name);

}  // namespace ddl::config
