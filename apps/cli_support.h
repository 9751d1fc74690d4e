#pragma once
// What every subcommand shares: error reporting with exit codes, the ../shared location, progress
// output and Ctrl-C handling. Lives in the app, never in the libraries.

#include <atomic>
#include <cstddef>
#include <functional>
#include <string>

namespace ddl::app {

/// Exit codes: 0 success, 1 failure while working, 2 bad input or configuration, 130 interrupted.
enum ExitCode : int { kOk = 0, kFailure = 1, kBadInput = 2, kInterrupted = 130 };

/// Runs a subcommand body, turning library exceptions into a one-line "error: ..." on stderr and
/// the matching exit code. Never lets an exception escape to terminate().
int run_guarded(const std::function<int()>& body);

/// The shared data folder: the flag value if given, else $DDL_SHARED_DIR, else ../shared. A folder
/// named by the flag or the variable must exist (InputError); the default may be missing.
std::string resolve_shared_dir(const std::string& flag_value);

/// Installs SIGINT/SIGTERM handlers that set the returned flag (first signal) so long work stops
/// cleanly and flushes its outputs; a second signal exits at once.
const std::atomic<bool>& install_stop_handler();

/// Progress on stderr: a redrawn bar on a terminal, otherwise a plain line every few seconds.
class Progress {
 public:
  Progress(std::string label, std::size_t total);
  ~Progress();
  Progress(const Progress&) = delete;
  Progress& operator=(const Progress&) = delete;
  void update(std::size_t done, const std::string& note = {});
  /// The last line, at the total.
  void finish(const std::string& note = {});
  /// The last line when the work stopped early (Ctrl-C): at the last count update() was given.
  void finish_early(const std::string& note);

 private:
  void finish_at(std::size_t done, const std::string& note);
  std::string label_;
  std::size_t total_;
  bool tty_;
  std::size_t done_ = 0;  // the last count update() was given
  bool finished_ = false;
  double start_s_;
  double last_print_s_ = -1e9;
};

}  // namespace ddl::app
