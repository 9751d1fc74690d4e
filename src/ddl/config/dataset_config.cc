#include "ddl/config/dataset_config.h"

#include <spdlog/spdlog.h>

#include "ddl/config/camera_config.h"
#include "ddl/core/error.h"

namespace ddl::config {

camera::PinholeCamera resolve_dataset_camera(const std::string& dir, const std::string& camera_arg,
                                             io::DatasetKind kind) {
  if (!camera_arg.empty()) return load_camera(camera_arg);
  const std::string chosen = io::default_camera_for(dir, kind);
  spdlog::info("{}: using camera '{}' (chosen from the folder; override with --camera)",
               io::sequence_name(dir), chosen);
  return load_camera(chosen);
}

io::DatasetOptions read_dataset_options(const YamlMap& map, io::DatasetOptions defaults) {
  io::DatasetOptions options = std::move(defaults);
  std::string text;
  if (map.read_choice("kind", text, {"auto", "tum", "bonn"})) {
    options.kind = io::parse_dataset_kind(text, map.key_path("kind"));
  }
  if (map.read_choice("associations", text, {"auto", "file", "timestamps"})) {
    options.sequence.association = io::parse_association_source(text, map.key_path("associations"));
  }
  map.read("associations_file", options.sequence.associations_file);
  map.read("max_difference", options.sequence.max_difference_s);
  map.read("check_files", options.sequence.check_files_on_open);
  try {
    options.sequence.validate();
  } catch (const ConfigError& e) {
    throw ConfigError(fmt::format("{}: {}", map.source(), e.what()));
  }
  return options;
}

}  // namespace ddl::config
