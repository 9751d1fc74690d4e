#include "ddl/core/error.h"

#include <string_view>

namespace ddl {

InputError InputError::at(const std::string& file, const std::string& what) {
  return InputError(fmt::format("{}: {}", file, what));
}

InputError InputError::at_line(const std::string& file, std::size_t line, const std::string& what) {
  return InputError(fmt::format("{}:{}: {}", file, line, what));
}

OutputError OutputError::at(const std::string& file, const std::string& what) {
  return OutputError(fmt::format("{}: {}", file, what));
}

ConfigError ConfigError::for_key(const std::string& key, const std::string& what) {
  return ConfigError(fmt::format("configuration key '{}': {}", key, what));
}

namespace {
// How for_key's messages name their key; with_key_prefix and key() find it by this.
constexpr std::string_view kKeyMarker = "key '";
}  // namespace

ConfigError ConfigError::with_key_prefix(const std::string& prefix) const {
  std::string message = what();
  if (const auto pos = message.find(kKeyMarker); pos != std::string::npos) {
    message.insert(pos + kKeyMarker.size(), prefix);
  }
  return ConfigError(message);
}

std::string ConfigError::key() const {
  const std::string message = what();
  const auto pos = message.find(kKeyMarker);
  if (pos == std::string::npos) return {};
  const std::size_t begin = pos + kKeyMarker.size();
  const auto end = message.find('\'', begin);
  return end == std::string::npos ? std::string() : message.substr(begin, end - begin);
}

}  // namespace ddl
