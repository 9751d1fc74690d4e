#include "cli_support.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>
#include <unistd.h>

#include <chrono>
#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <filesystem>

#include "ddl/core/error.h"

namespace ddl::app {
namespace {

// Signal handlers can only reach static storage; this is the app's single such flag.
std::atomic<bool> g_stop_requested{false};

extern "C" void on_signal(int) {
  if (g_stop_requested.exchange(true)) {
    // Only async-signal-safe calls here: write(2) and _Exit.
    constexpr char kQuit[] =
        "\nsecond interrupt: exiting at once; the outputs of this run are NOT saved (each file in "
        "the output folder is whole: from this run, from an earlier one, or missing)\n";
    [[maybe_unused]] auto n = write(STDERR_FILENO, kQuit, sizeof(kQuit) - 1);
    std::_Exit(kInterrupted);
  }
  constexpr char kMsg[] =
      "\nstopping: finishing the current frame and saving outputs (interrupt again to quit at "
      "once without saving)...\n";
  [[maybe_unused]] auto n = write(STDERR_FILENO, kMsg, sizeof(kMsg) - 1);
}

double now_s() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

}  // namespace

int run_guarded(const std::function<int()>& body) {
  try {
    return body();
  } catch (const Interrupted&) {
    std::fprintf(stderr, "interrupted: outputs written so far were saved\n");
    return kInterrupted;
  } catch (const InputError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kBadInput;
  } catch (const ConfigError& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kBadInput;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "error: %s\n", e.what());
    return kFailure;
  }
}

std::string resolve_shared_dir(const std::string& flag_value) {
  // A folder the user named must be there; only the built-in default may be missing (a fresh
  // machine: geometry-only dynamics, procedural people, with warnings).
  const auto named = [](const std::string& dir, const char* by) {
    std::error_code ec;
    if (!std::filesystem::is_directory(dir, ec)) {
      throw InputError::at(dir, fmt::format("shared data folder ({}) not found", by));
    }
    return dir;
  };
  if (!flag_value.empty()) return named(flag_value, "--shared-dir");
  if (const char* env = std::getenv("DDL_SHARED_DIR"); env != nullptr && *env != '\0') {
    return named(env, "$DDL_SHARED_DIR");
  }
  return "../shared";
}

const std::atomic<bool>& install_stop_handler() {
  struct sigaction action {};
  action.sa_handler = on_signal;
  sigemptyset(&action.sa_mask);
  sigaction(SIGINT, &action, nullptr);
  sigaction(SIGTERM, &action, nullptr);
  return g_stop_requested;
}

Progress::Progress(std::string label, std::size_t total)
    : label_(std::move(label)),
      total_(total),
      tty_(isatty(STDERR_FILENO) != 0),
      start_s_(now_s()) {}

Progress::~Progress() {
  if (tty_ && !finished_ && last_print_s_ > -1e9) std::fputc('\n', stderr);
}

void Progress::update(std::size_t done, const std::string& note) {
  done_ = done;
  const double t = now_s();
  const double interval = tty_ ? 0.1 : 5.0;
  if (t - last_print_s_ < interval && done < total_) return;
  last_print_s_ = t;
  const double frac = total_ == 0 ? 1.0 : static_cast<double>(done) / static_cast<double>(total_);
  const double elapsed = t - start_s_;
  const double rate = elapsed > 0 ? static_cast<double>(done) / elapsed : 0.0;
  if (tty_) {
    constexpr int kWidth = 30;
    const int filled = static_cast<int>(frac * kWidth);
    std::string bar(static_cast<std::size_t>(filled), '#');
    bar.resize(kWidth, '.');
    std::fprintf(stderr, "\r%s [%s] %zu/%zu %5.1f/s %s\033[K", label_.c_str(), bar.c_str(), done,
                 total_, rate, note.c_str());
  } else {
    std::fprintf(stderr, "%s: %zu/%zu (%.0f%%) %.1f/s %s\n", label_.c_str(), done, total_,
                 100.0 * frac, rate, note.c_str());
  }
  std::fflush(stderr);
}

void Progress::finish(const std::string& note) { finish_at(total_, note); }

void Progress::finish_early(const std::string& note) { finish_at(done_, note); }

void Progress::finish_at(std::size_t done, const std::string& note) {
  if (finished_) return;
  last_print_s_ = -1e9;
  update(done, note);
  if (tty_) std::fputc('\n', stderr);
  finished_ = true;
}

}  // namespace ddl::app
