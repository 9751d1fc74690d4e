#include "ddl/config/yaml_reader.h"

#include <fmt/format.h>

#include <algorithm>
#include <cerrno>
#include <climits>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <sstream>

#include "ddl/core/error.h"

namespace ddl::config {

namespace detail {
struct YamlContext {
  std::string source;
  YAML::Node root;
  std::set<std::string> asked;   // dotted paths any reader asked for (present or not)
  std::set<std::string> opened;  // dotted paths of maps handed out by get_map/find_map
};
}  // namespace detail

namespace {

std::string join(const std::string& path, const std::string& key) {
  return path.empty() ? key : path + "." + key;
}

int line_of_node(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  return mark.is_null() ? 0 : mark.line + 1;
}

std::string where(const std::string& source, int line) {
  return line > 0 ? fmt::format("{}:{}", source, line) : source;
}

const char* type_name(const YAML::Node& node) {
  switch (node.Type()) {
    case YAML::NodeType::Null:
      return "nothing (null)";
    case YAML::NodeType::Scalar:
      return "a scalar";
    case YAML::NodeType::Sequence:
      return "a list";
    case YAML::NodeType::Map:
      return "a map";
    case YAML::NodeType::Undefined:
      return "nothing";
  }
  return "?";
}

// What the user wrote, for messages.
std::string shown(const YAML::Node& node) {
  if (node.IsScalar()) return fmt::format("'{}'", node.Scalar());
  return type_name(node);
}

std::optional<double> parse_number(const std::string& text) {
  // YAML 1.2 core schema spellings of the special values.
  static const std::map<std::string, double> kSpecial = {
      {".inf", std::numeric_limits<double>::infinity()},
      {".Inf", std::numeric_limits<double>::infinity()},
      {".INF", std::numeric_limits<double>::infinity()},
      {"+.inf", std::numeric_limits<double>::infinity()},
      {"+.Inf", std::numeric_limits<double>::infinity()},
      {"+.INF", std::numeric_limits<double>::infinity()},
      {"-.inf", -std::numeric_limits<double>::infinity()},
      {"-.Inf", -std::numeric_limits<double>::infinity()},
      {"-.INF", -std::numeric_limits<double>::infinity()},
      {".nan", std::numeric_limits<double>::quiet_NaN()},
      {".NaN", std::numeric_limits<double>::quiet_NaN()},
      {".NAN", std::numeric_limits<double>::quiet_NaN()}};
  if (const auto it = kSpecial.find(text); it != kSpecial.end()) return it->second;
  if (text.empty()) return std::nullopt;
  // Decimal only: digits, sign, point, exponent (rejects "inf", "nan", hex, "1,5", "0x10").
  for (char c : text) {
    if (!((c >= '0' && c <= '9') || c == '+' || c == '-' || c == '.' || c == 'e' || c == 'E')) {
      return std::nullopt;
    }
  }
  errno = 0;
  char* end = nullptr;
  const double value = std::strtod(text.c_str(), &end);
  if (end != text.c_str() + text.size()) return std::nullopt;
  if (errno == ERANGE && std::abs(value) > 1.0) return std::nullopt;
  return value;
}

std::optional<long long> parse_integer(const std::string& text) {
  if (text.empty()) return std::nullopt;
  std::size_t start = (text[0] == '+' || text[0] == '-') ? 1 : 0;
  if (start == text.size()) return std::nullopt;
  for (std::size_t i = start; i < text.size(); ++i) {
    if (text[i] < '0' || text[i] > '9') return std::nullopt;
  }
  errno = 0;
  const long long value = std::strtoll(text.c_str(), nullptr, 10);
  if (errno == ERANGE) return std::nullopt;
  return value;
}

// Edits (insert, delete, substitute, swap two neighbours) turning a into b: optimal string
// alignment distance, so "fsp" is one edit from "fps".
std::size_t edit_distance(const std::string& a, const std::string& b) {
  const std::size_t n = a.size(), m = b.size();
  std::vector<std::size_t> d((n + 1) * (m + 1));
  const auto at = [&](std::size_t i, std::size_t j) -> std::size_t& { return d[i * (m + 1) + j]; };
  for (std::size_t i = 0; i <= n; ++i) at(i, 0) = i;
  for (std::size_t j = 0; j <= m; ++j) at(0, j) = j;
  for (std::size_t i = 1; i <= n; ++i) {
    for (std::size_t j = 1; j <= m; ++j) {
      const std::size_t cost = a[i - 1] == b[j - 1] ? 0 : 1;
      at(i, j) = std::min({at(i - 1, j) + 1, at(i, j - 1) + 1, at(i - 1, j - 1) + cost});
      if (i > 1 && j > 1 && a[i - 1] == b[j - 2] && a[i - 2] == b[j - 1]) {
        at(i, j) = std::min(at(i, j), at(i - 2, j - 2) + 1);
      }
    }
  }
  return at(n, m);
}

// Whether `written` looks like a misspelling of `wanted` (one or two edits, not identical).
bool is_near_miss(const std::string& written, const std::string& wanted) {
  const std::size_t d = edit_distance(written, wanted);
  return d > 0 && d <= std::max<std::size_t>(1, std::min<std::size_t>(2, wanted.size() / 3));
}

std::string format_choices(std::initializer_list<std::string_view> choices) {
  std::string out;
  for (std::string_view c : choices) {
    if (!out.empty()) out += ", ";
    out += c;
  }
  return out;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// YamlMap

YamlMap::YamlMap(std::shared_ptr<detail::YamlContext> context, YAML::Node node, std::string path)
    : context_(std::move(context)), node_(std::move(node)), path_(std::move(path)) {}

const std::string& YamlMap::source() const { return context_->source; }

std::string YamlMap::key_path(const std::string& key) const { return join(path_, key); }

bool YamlMap::has(const std::string& key) const {
  context_->asked.insert(key_path(key));
  if (!node_.IsMap()) return false;
  return static_cast<bool>(node_[key]);
}

std::vector<std::string> YamlMap::keys() const {
  std::vector<std::string> out;
  if (!node_.IsMap()) return out;
  for (const auto& kv : node_) out.push_back(kv.first.IsScalar() ? kv.first.Scalar() : "?");
  return out;
}

int YamlMap::line_of(const std::string& key) const {
  if (!node_.IsMap()) return 0;
  const YAML::Node value = node_[key];
  return value ? line_of_node(value) : 0;
}

void YamlMap::fail(const std::string& key, const std::string& what) const {
  const int line = line_of(key);
  throw ConfigError(fmt::format(
      "{}: {}: {}", where(source(), line > 0 ? line : line_of_node(node_)), key_path(key), what));
}

YAML::Node YamlMap::value_node(const std::string& key) const {
  context_->asked.insert(key_path(key));
  if (!node_.IsMap()) return YAML::Node(YAML::NodeType::Undefined);
  // const access: never inserts the key.
  const YAML::Node& const_node = node_;
  return const_node[key];
}

YAML::Node YamlMap::required(const std::string& key, const char* expected) const {
  YAML::Node value = value_node(key);
  if (!value) {
    // A key of this map one or two edits away is most likely a typo of the missing one.
    std::string hint;
    if (node_.IsMap()) {
      for (const auto& kv : node_) {
        if (kv.first.IsScalar() && is_near_miss(kv.first.Scalar(), key)) {
          hint = fmt::format("; is '{}' on line {} a typo?", key_path(kv.first.Scalar()),
                             line_of_node(kv.first));
          break;
        }
      }
    }
    const int line = line_of_node(node_);
    throw ConfigError(fmt::format("{}: missing required key '{}' ({}){}",
                                  path_.empty() ? source() : where(source(), line), key_path(key),
                                  expected, hint));
  }
  return value;
}

double YamlMap::get_double(const std::string& key) const {
  const YAML::Node value = required(key, "a number");
  if (value.IsScalar()) {
    if (const std::optional<double> number = parse_number(value.Scalar())) return *number;
  }
  fail(key, fmt::format("expected a number, got {}", shown(value)));
}

int YamlMap::get_int(const std::string& key) const {
  const YAML::Node value = required(key, "an integer");
  if (value.IsScalar()) {
    const std::optional<long long> number = parse_integer(value.Scalar());
    if (number && *number >= INT_MIN && *number <= INT_MAX) return static_cast<int>(*number);
  }
  fail(key, fmt::format("expected an integer, got {}", shown(value)));
}

bool YamlMap::get_bool(const std::string& key) const {
  const YAML::Node value = required(key, "true or false");
  if (value.IsScalar()) {
    const std::string& s = value.Scalar();
    if (s == "true" || s == "True" || s == "TRUE") return true;
    if (s == "false" || s == "False" || s == "FALSE") return false;
  }
  fail(key, fmt::format("expected true or false, got {}", shown(value)));
}

std::string YamlMap::get_string(const std::string& key) const {
  const YAML::Node value = required(key, "a string");
  if (!value.IsScalar()) fail(key, fmt::format("expected a string, got {}", type_name(value)));
  return value.Scalar();
}

std::string YamlMap::get_choice(const std::string& key,
                                std::initializer_list<std::string_view> choices) const {
  const std::string value = get_string(key);
  for (std::string_view c : choices) {
    if (value == c) return value;
  }
  fail(key, fmt::format("'{}' is not one of {}", value, format_choices(choices)));
}

std::vector<double> YamlMap::get_doubles(const std::string& key, std::size_t expected_size) const {
  const YAML::Node value = required(key, "a list of numbers");
  if (!value.IsSequence()) {
    fail(key, fmt::format("expected a list of numbers [a, b, ...], got {}", shown(value)));
  }
  if (expected_size != 0 && value.size() != expected_size) {
    fail(key, fmt::format("expected a list of {} numbers, got {}", expected_size, value.size()));
  }
  std::vector<double> out;
  out.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) {
    const YAML::Node item = value[i];
    std::optional<double> number;
    if (item.IsScalar()) number = parse_number(item.Scalar());
    if (!number) {
      throw ConfigError(fmt::format("{}: {}[{}]: expected a number, got {}",
                                    where(source(), line_of_node(item)), key_path(key), i,
                                    shown(item)));
    }
    out.push_back(*number);
  }
  return out;
}

YamlMap YamlMap::get_map(const std::string& key) const {
  const YAML::Node value = required(key, "a map of keys");
  if (!value.IsMap()) fail(key, fmt::format("expected a map of keys, got {}", shown(value)));
  context_->opened.insert(key_path(key));
  return YamlMap(context_, value, key_path(key));
}

std::optional<YamlMap> YamlMap::find_map(const std::string& key) const {
  if (!has(key)) return std::nullopt;
  return get_map(key);
}

bool YamlMap::read(const std::string& key, double& value) const {
  if (!has(key)) return false;
  value = get_double(key);
  return true;
}

bool YamlMap::read(const std::string& key, int& value) const {
  if (!has(key)) return false;
  value = get_int(key);
  return true;
}

bool YamlMap::read(const std::string& key, bool& value) const {
  if (!has(key)) return false;
  value = get_bool(key);
  return true;
}

bool YamlMap::read(const std::string& key, std::string& value) const {
  if (!has(key)) return false;
  value = get_string(key);
  return true;
}

bool YamlMap::read(const std::string& key, std::vector<double>& value) const {
  if (!has(key)) return false;
  value = get_doubles(key);
  return true;
}

std::vector<std::string> YamlMap::get_strings(const std::string& key) const {
  const YAML::Node value = required(key, "a list of strings");
  if (!value.IsSequence()) {
    fail(key, fmt::format("expected a list of strings [a, b, ...], got {}", shown(value)));
  }
  std::vector<std::string> out;
  out.reserve(value.size());
  for (std::size_t i = 0; i < value.size(); ++i) {
    const YAML::Node item = value[i];
    if (!item.IsScalar()) {
      throw ConfigError(fmt::format("{}: {}[{}]: expected a string, got {}",
                                    where(source(), line_of_node(item)), key_path(key), i,
                                    shown(item)));
    }
    out.push_back(item.Scalar());
  }
  return out;
}

bool YamlMap::read(const std::string& key, std::vector<std::string>& value) const {
  if (!has(key)) return false;
  value = get_strings(key);
  return true;
}

bool YamlMap::read_choice(const std::string& key, std::string& value,
                          std::initializer_list<std::string_view> choices) const {
  if (!has(key)) return false;
  value = get_choice(key, choices);
  return true;
}

// ---------------------------------------------------------------------------------------------
// YamlFile

YamlFile::YamlFile(std::shared_ptr<detail::YamlContext> context) : context_(std::move(context)) {}

YamlFile YamlFile::load(const std::string& path) {
  std::error_code ec;
  if (!std::filesystem::exists(path, ec)) throw InputError::at(path, "file not found");
  if (std::filesystem::is_directory(path, ec)) {
    throw InputError::at(path, "is a directory, not a file");
  }
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError::at(path, "cannot open for reading");
  std::ostringstream text;
  text << file.rdbuf();
  if (file.bad()) throw InputError::at(path, "read error");
  return parse(text.str(), path);
}

YamlFile YamlFile::parse(const std::string& text, const std::string& source_name) {
  auto context = std::make_shared<detail::YamlContext>();
  context->source = source_name;
  try {
    const std::vector<YAML::Node> documents = YAML::LoadAll(text);
    if (documents.size() > 1) {
      throw ConfigError(
          fmt::format("{}: holds {} YAML documents (separated by '---'); settings take exactly one",
                      source_name, documents.size()));
    }
    if (!documents.empty()) context->root.reset(documents.front());
  } catch (const YAML::ParserException& e) {
    throw ConfigError(fmt::format(
        "{}: YAML syntax error: {}",
        e.mark.is_null() ? source_name
                         : fmt::format("{}:{}:{}", source_name, e.mark.line + 1, e.mark.column + 1),
        e.msg));
  } catch (const YAML::Exception& e) {
    throw ConfigError(fmt::format("{}: YAML error: {}", source_name, e.what()));
  }
  if (!context->root.IsNull() && !context->root.IsMap()) {
    throw ConfigError(fmt::format("{}: expected a map of keys at the top level, got {}",
                                  where(source_name, line_of_node(context->root)),
                                  type_name(context->root)));
  }
  return YamlFile(std::move(context));
}

const std::string& YamlFile::source() const { return context_->source; }

YamlMap YamlFile::root() const { return YamlMap(context_, context_->root, ""); }

int YamlFile::line_of_path(const std::string& dotted_key) const {
  // A handle on the root; reset() rebinds it (assignment would write into the document), and
  // lookups go through a const reference, whose operator[] never inserts.
  YAML::Node node;
  node.reset(context_->root);
  std::size_t begin = 0;
  while (true) {
    if (!node.IsMap()) return 0;
    const std::size_t dot = dotted_key.find('.', begin);
    const std::string part = dotted_key.substr(begin, dot == std::string::npos ? dot : dot - begin);
    const YAML::Node& map = node;
    const YAML::Node next = map[part];
    if (!next) return 0;
    if (dot == std::string::npos) return line_of_node(next);
    node.reset(next);
    begin = dot + 1;
  }
}

void YamlFile::check_all_keys_used() const {
  const detail::YamlContext& ctx = *context_;
  // Depth-first in file order, so the first problem reported is the first in the file.
  auto walk = [&](const auto& self, const YAML::Node& map, const std::string& path) -> void {
    std::set<std::string> seen;
    for (const auto& kv : map) {
      if (!kv.first.IsScalar()) {
        throw ConfigError(fmt::format("{}: {}: keys must be plain names, got {}",
                                      where(ctx.source, line_of_node(kv.first)),
                                      path.empty() ? "<top level>" : path, type_name(kv.first)));
      }
      const std::string& key = kv.first.Scalar();
      const std::string full = join(path, key);
      const int line = line_of_node(kv.first);
      if (!seen.insert(key).second) {
        throw ConfigError(
            fmt::format("duplicate key '{}' in {} (line {})", full, ctx.source, line));
      }
      if (ctx.asked.count(full) == 0) {
        // Suggest a key a reader asked for in the same map that the file does not give.
        std::string best;
        std::size_t best_distance = std::string::npos;
        for (const std::string& candidate : ctx.asked) {
          const std::size_t dot = candidate.rfind('.');
          const std::string parent = dot == std::string::npos ? "" : candidate.substr(0, dot);
          const std::string leaf = dot == std::string::npos ? candidate : candidate.substr(dot + 1);
          if (parent != path || map[leaf] || !is_near_miss(key, leaf)) continue;
          const std::size_t d = edit_distance(key, leaf);
          if (d < best_distance) {
            best_distance = d;
            best = candidate;
          }
        }
        throw ConfigError(
            fmt::format("unknown key '{}' in {} (line {}){}", full, ctx.source, line,
                        best.empty() ? "" : fmt::format("; did you mean '{}'?", best)));
      }
      if (kv.second.IsMap() && ctx.opened.count(full) != 0) self(self, kv.second, full);
    }
  };
  if (ctx.root.IsMap()) walk(walk, ctx.root, "");
}

}  // namespace ddl::config
