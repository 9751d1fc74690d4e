// ddl_slam: the single command-line entry point. Thin: parses flags, calls the libraries.

#include <spdlog/sinks/stdout_color_sinks.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <CLI/CLI.hpp>
#include <string>

#include "cli_support.h"
#include "commands.h"

int main(int argc, char** argv) {
  CLI::App app{
      "DDL-SLAM: RGB-D SLAM for dynamic scenes (CNN + multi-view geometry dynamic removal, "
      "background inpainting, OctoMap), with TUM-exact evaluation."};
  app.require_subcommand(1);
  app.set_version_flag("--version", "ddl_slam 0.1.0");
  std::string log_level = "info";
  app.add_option("--log-level", log_level, "Log level: trace, debug, info, warn, error, off")
      ->check(CLI::IsMember({"trace", "debug", "info", "warn", "error", "off"}))
      ->capture_default_str();
  app.parse_complete_callback([&] { spdlog::set_level(spdlog::level::from_str(log_level)); });
  // The log is diagnostics: it goes to stderr, beside the progress, so that stdout holds only what
  // a command reports (eval's report, bench's tables, run's summary line) for a script to read.
  spdlog::set_default_logger(spdlog::stderr_color_mt("ddl_slam"));
  // On a terminal a log line first clears the progress bar's line (redrawn with \r), instead of
  // being glued onto it; the bar is drawn again at its next update.
  spdlog::set_pattern(isatty(STDERR_FILENO) != 0 ? "\r\033[K[%H:%M:%S.%e] [%^%l%$] %v"
                                                 : "[%H:%M:%S.%e] [%^%l%$] %v");

  int exit_code = ddl::app::kOk;
  ddl::app::add_run_command(app, exit_code);
  ddl::app::add_eval_command(app, exit_code);
  ddl::app::add_bench_command(app, exit_code);
  ddl::app::add_eval_dense_command(app, exit_code);
  ddl::app::add_vocab_command(app, exit_code);
  ddl::app::add_synth_command(app, exit_code);
  ddl::app::add_config_command(app, exit_code);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : ddl::app::kBadInput;
  }
  return exit_code;
}
