// `ddl_slam config`: print the default settings as YAML, check a settings file, or print the
// Markdown reference of every key.

#include <CLI/CLI.hpp>
#include <cstdio>
#include <memory>
#include <string>

#include "cli_support.h"
#include "commands.h"
#include "ddl/config/system_config.h"

namespace ddl::app {

void add_config_command(CLI::App& app, int& exit_code) {
  struct Args {
    std::string check;
    bool reference = false;
  };
  auto args = std::make_shared<Args>();
  CLI::App* cmd = app.add_subcommand(
      "config",
      "Print the default settings as YAML (a starting point for run --config), check a settings "
      "file (--check FILE: unknown keys and invalid values are errors naming file, line and key), "
      "or print the Markdown reference of every setting (--reference).");
  CLI::Option* check = cmd->add_option("--check", args->check,
                                       "Settings file to validate; prints its effective values");
  cmd->add_flag("--reference", args->reference, "Print the Markdown table of every key")
      ->excludes(check);
  cmd->callback([args, &exit_code] {
    exit_code = run_guarded([&] {
      if (args->reference) {
        std::fputs(config::system_config_reference_markdown().c_str(), stdout);
      } else if (!args->check.empty()) {
        std::fputs(config::system_config_to_yaml(config::load_system_config(args->check)).c_str(),
                   stdout);
      } else {
        std::fputs(config::system_config_to_yaml(pipeline::SystemConfig{}).c_str(), stdout);
      }
      return kOk;
    });
  });
}

}  // namespace ddl::app
