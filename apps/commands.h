#pragma once
// Each subcommand adds itself to the CLI and, when run, stores its exit code in `exit_code`.

#include <CLI/CLI.hpp>

namespace ddl::app {

void add_eval_command(CLI::App& app, int& exit_code);

}  // namespace ddl::app
