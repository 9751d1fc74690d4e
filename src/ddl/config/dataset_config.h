#pragma once
// Dataset configuration: picking the camera of a sequence folder and reading the `dataset:`
// section of a configuration file. Lives in config because it reads YAML; io stays YAML-free.
// Threads: free functions without shared state; callable from any thread.

#include <string>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/config/yaml_reader.h"
#include "ddl/io/dataset_factory.h"

namespace ddl::config {

/// The camera of the sequence in `dir`: `camera_arg` (a builtin name or a YAML file path) when not
/// empty, else the folder's default (io::default_camera_for: freiburg1/2/3 -> tum1/2/3,
/// rgbd_bonn_* or kind bonn -> bonn, else <dir>/camera.yaml), loaded with load_camera().
/// Throws ddl::InputError (no default applies: the message tells the user to pass --camera; or a
/// file problem) or ddl::ConfigError (invalid camera file).
camera::PinholeCamera resolve_dataset_camera(const std::string& dir, const std::string& camera_arg,
                                             io::DatasetKind kind = io::DatasetKind::kAuto);

/// Reads the optional keys of a `dataset:` map over `defaults` (camera untouched):
///   kind: auto|tum|bonn            associations: auto|file|timestamps
///   associations_file: PATH        max_difference: SECONDS        check_files: true|false
/// Validates the sequence options. Unknown keys are reported by the YamlFile's owner
/// (YamlFile::check_all_keys_used).
io::DatasetOptions read_dataset_options(const YamlMap& dataset_map,
                                        io::DatasetOptions defaults = {});

}  // namespace ddl::config
