#pragma once
// Exceptions thrown at the library's boundaries (files, configuration, models). Per-frame outcomes
// are values, never exceptions (ARCHITECTURE.md section 5).

#include <fmt/format.h>

#include <stdexcept>
#include <string>

namespace ddl {

/// Base of every error the library throws. The message is complete and user-facing.
class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

/// A file or directory given as input is missing, unreadable or malformed. The message names the
/// file and, where it applies, the line (1-based) and what was wrong.
class InputError : public Error {
 public:
  using Error::Error;
  static InputError at(const std::string& file, const std::string& what);
  static InputError at_line(const std::string& file, std::size_t line, const std::string& what);
};

/// An output file could not be written (no space, no permission, an I/O error). The message
/// names the file and what it was for.
class OutputError : public Error {
 public:
  using Error::Error;
  static OutputError at(const std::string& file, const std::string& what);
};

/// A configuration key is unknown or holds an invalid value. The message names the key.
class ConfigError : public Error {
 public:
  using Error::Error;
  static ConfigError for_key(const std::string& key, const std::string& what);
  /// The same error with `prefix` put before the key it names ("optimizer.x" ->
  /// "loop.optimizer.x"), for a config struct validated inside an enclosing one.
  ConfigError with_key_prefix(const std::string& prefix) const;
  /// The dotted key the message names ("tracking.orb.scale_factor"), empty when it names none.
  std::string key() const;
};

/// Thrown by a pipeline that was asked to stop (Ctrl-C); outputs so far have been flushed.
class Interrupted : public Error {
 public:
  Interrupted() : Error("interrupted") {}
};

}  // namespace ddl
