#pragma once
// The system settings file (YAML): every field of pipeline::SystemConfig and the stage configs it
// holds, read strictly (unknown keys are errors naming file, line and key; values are validated
// by each struct's validate()), written back as the effective configuration of a run, and listed
// with defaults and one-line documentation for docs/configuration.md. The field lists come from
// config_fields.inc, generated from the structs by scripts/gen_config_fields.py.

#include <string>

#include "ddl/pipeline/system_config.h"

namespace ddl::config {

/// Reads a settings file over the defaults; keys absent from the file keep their defaults.
/// Throws ddl::InputError (file) or ddl::ConfigError (syntax, unknown key, bad value).
pipeline::SystemConfig load_system_config(const std::string& path);
/// The same from text (`source_name` is used in messages).
pipeline::SystemConfig parse_system_config(const std::string& yaml, const std::string& source_name);

/// The effective configuration as YAML that load_system_config reads back to the same values.
std::string system_config_to_yaml(const pipeline::SystemConfig& config);

/// Markdown reference of every key with its default and documentation.
std::string system_config_reference_markdown();

pipeline::RunMode parse_run_mode(const std::string& text, const std::string& key);
segmentation::Backend parse_segmentation_backend(const std::string& text, const std::string& key);

/// The vocabulary shipped with the sources (vocab/ in the source tree, found at build time).
std::string default_vocabulary_path();

}  // namespace ddl::config
