#include "ddl/core/error.h"

namespace ddl {

InputError InputError::at(const std::string& file, const std::string& what) {
  return InputError(fmt::format("{}: {}", file, what));
}

InputError InputError::at_line(const std::string& file, std::size_t line, const std::string& what) {
  return InputError(fmt::format("{}:{}: {}", file, line, what));
}

ConfigError ConfigError::for_key(const std::string& key, const std::string& what) {
  return ConfigError(fmt::format("configuration key '{}': {}", key, what));
}

ConfigError ConfigError::with_key_prefix(const std::string& prefix) const {
  std::string message = what();
  const std::string marker = "key '";
  if (const auto pos = message.find(marker); pos != std::string::npos) {
    message.insert(pos + marker.size(), prefix);
  }
  return ConfigError(message);
}

}  // namespace ddl
