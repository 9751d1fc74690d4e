#include "ddl/vocabulary/vocabulary_config.h"

#include <fmt/format.h>

#include "ddl/core/error.h"

namespace ddl::vocabulary {

std::string_view to_string(Weighting weighting) {
  switch (weighting) {
    case Weighting::kTfIdf:
      return "tf-idf";
    case Weighting::kTf:
      return "tf";
    case Weighting::kIdf:
      return "idf";
    case Weighting::kBinary:
      return "binary";
  }
  return "unknown";
}

std::optional<Weighting> parse_weighting(std::string_view name) {
  for (Weighting w : {Weighting::kTfIdf, Weighting::kTf, Weighting::kIdf, Weighting::kBinary}) {
    if (to_string(w) == name) return w;
  }
  return std::nullopt;
}

void VocabularyConfig::validate() const {
  const auto require = [](bool ok, const char* key, const std::string& what) {
    if (!ok) throw ConfigError::for_key(key, what);
  };
  require(branching >= 2 && branching <= 64, "branching",
          fmt::format("must be in [2, 64], got {}", branching));
  require(levels >= 1 && levels <= 10, "levels", fmt::format("must be in [1, 10], got {}", levels));
  require(max_iterations >= 1 && max_iterations <= 1000, "max_iterations",
          fmt::format("must be in [1, 1000], got {}", max_iterations));
  require(threads >= 1 && threads <= 256, "threads",
          fmt::format("must be in [1, 256], got {}", threads));
  require(parse_weighting(to_string(weighting)).has_value(), "weighting",
          fmt::format("must be tf-idf, tf, idf or binary, got value {}",
                      static_cast<std::uint32_t>(weighting)));
}

}  // namespace ddl::vocabulary
