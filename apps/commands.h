#pragma once
// Each subcommand adds itself to the CLI and, when run, stores its exit code in `exit_code`.

#include <CLI/CLI.hpp>

namespace ddl::app {

void add_eval_command(CLI::App& app, int& exit_code);
void add_bench_command(CLI::App& app, int& exit_code);
void add_eval_dense_command(CLI::App& app, int& exit_code);
void add_run_command(CLI::App& app, int& exit_code);
void add_config_command(CLI::App& app, int& exit_code);
void add_vocab_command(CLI::App& app, int& exit_code);
void add_synth_command(CLI::App& app, int& exit_code);

}  // namespace ddl::app
