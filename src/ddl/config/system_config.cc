#include "ddl/config/system_config.h"

#include <fmt/format.h>

#include <cmath>
#include <limits>
#include <sstream>
#include <type_traits>

#include "ddl/config/yaml_reader.h"
#include "ddl/core/error.h"

namespace ddl::config {

// The generated visit() overloads, one per configuration struct.
#include "ddl/config/config_fields.inc"

static_assert(std::is_same_v<std::size_t, std::uint64_t>,
              "the readers below treat std::size_t as std::uint64_t");

namespace {

// --- enums <-> text ----------------------------------------------------------------------------

template <class E>
struct EnumNames;

template <>
struct EnumNames<pipeline::RunMode> {
  static constexpr std::pair<pipeline::RunMode, const char*> kValues[] = {
      {pipeline::RunMode::kDeterministic, "deterministic"},
      {pipeline::RunMode::kThreaded, "threaded"}};
};

template <>
struct EnumNames<segmentation::Backend> {
  static constexpr std::pair<segmentation::Backend, const char*> kValues[] = {
      {segmentation::Backend::kOnnx, "onnx"},
      {segmentation::Backend::kFolder, "folder"},
      {segmentation::Backend::kNone, "none"}};
};

template <>
struct EnumNames<dynamics::GrowthVeto> {
  static constexpr std::pair<dynamics::GrowthVeto, const char*> kValues[] = {
      {dynamics::GrowthVeto::kAll, "all"}, {dynamics::GrowthVeto::kAnyUnrefuted, "any_unrefuted"}};
};

template <>
struct EnumNames<optimization::BaLinearSolver> {
  static constexpr std::pair<optimization::BaLinearSolver, const char*> kValues[] = {
      {optimization::BaLinearSolver::kAuto, "auto"},
      {optimization::BaLinearSolver::kDenseSchur, "dense_schur"},
      {optimization::BaLinearSolver::kSparseSchur, "sparse_schur"},
      {optimization::BaLinearSolver::kIterativeSchur, "iterative_schur"}};
};

template <class E>
const char* enum_name(E value) {
  for (const auto& [v, name] : EnumNames<E>::kValues) {
    if (v == value) return name;
  }
  return "?";
}

template <class E>
E enum_value(const std::string& text, const std::string& key) {
  std::string choices;
  for (const auto& [v, name] : EnumNames<E>::kValues) {
    if (text == name) return v;
    choices += (choices.empty() ? "" : ", ") + std::string(name);
  }
  throw ConfigError::for_key(key, fmt::format("'{}' is not one of: {}", text, choices));
}

// --- reading -------------------------------------------------------------------------------------

class Reader {
 public:
  explicit Reader(YamlMap map) : map_(std::move(map)) {}

  void field(const char* key, int& v, const char*) { map_.read(key, v); }
  void field(const char* key, double& v, const char*) { map_.read(key, v); }
  void field(const char* key, bool& v, const char*) { map_.read(key, v); }
  void field(const char* key, std::string& v, const char*) { map_.read(key, v); }
  void field(const char* key, std::vector<std::string>& v, const char*) { map_.read(key, v); }
  void field(const char* key, float& v, const char*) {
    double d = v;
    if (map_.read(key, d)) v = static_cast<float>(d);
  }
  // std::size_t and std::uint64_t are one type here (static_assert below).
  void field(const char* key, std::uint64_t& v, const char*) {
    double d = 0;
    if (!map_.read(key, d)) return;
    if (d < 0 || d != std::floor(d) || d > 9.0e15) {
      map_.fail(key, fmt::format("must be a non-negative integer, got {}", d));
    }
    v = static_cast<std::uint64_t>(d);
  }
  template <class S>
  void section(const char* key, S& sub, const char*) {
    if (auto m = map_.find_map(key)) {
      Reader reader(*m);
      visit(reader, sub);
    }
  }
  template <class E>
  void choice(const char* key, E& value, const char*) {
    std::string text;
    if (!map_.read(key, text)) return;
    try {
      value = enum_value<E>(text, map_.key_path(key));
    } catch (const ConfigError& e) {
      map_.fail(key, e.what());
    }
  }

 private:
  YamlMap map_;
};

// --- writing -------------------------------------------------------------------------------------

std::string format_double(double v) {
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  std::string s = fmt::format("{}", v);
  if (s.find_first_of(".eE") == std::string::npos && s.find("inf") == std::string::npos &&
      s.find("nan") == std::string::npos) {
    s += ".0";
  }
  return s;
}

std::string quote(const std::string& s) {
  std::string out = "\"";
  for (char c : s) {
    if (c == '"' || c == '\\') out += '\\';
    out += c;
  }
  return out + "\"";
}

class Writer {
 public:
  explicit Writer(std::ostringstream& out, int indent = 0) : out_(out), indent_(indent) {}

  void field(const char* key, int v, const char* doc) { line(key, fmt::format("{}", v), doc); }
  void field(const char* key, double v, const char* doc) { line(key, format_double(v), doc); }
  void field(const char* key, float v, const char* doc) {
    // Shortest text that reads back to the same float (0.7f prints "0.7", not 0.69999...).
    std::string s = fmt::format("{}", v);
    if (s.find_first_of(".eEn") == std::string::npos) s += ".0";
    line(key, s, doc);
  }
  void field(const char* key, bool v, const char* doc) { line(key, v ? "true" : "false", doc); }
  void field(const char* key, std::uint64_t v, const char* doc) {
    line(key, fmt::format("{}", v), doc);
  }
  void field(const char* key, const std::string& v, const char* doc) { line(key, quote(v), doc); }
  void field(const char* key, const std::vector<std::string>& v, const char* doc) {
    std::string list = "[";
    for (std::size_t i = 0; i < v.size(); ++i) list += (i ? ", " : "") + quote(v[i]);
    line(key, list + "]", doc);
  }
  template <class S>
  void section(const char* key, S& sub, const char* doc) {
    comment(doc);
    out_ << std::string(static_cast<std::size_t>(indent_), ' ') << key << ":\n";
    Writer nested(out_, indent_ + 2);
    visit(nested, sub);
  }
  template <class E>
  void choice(const char* key, E value, const char* doc) {
    std::string choices;
    for (const auto& [v, name] : EnumNames<E>::kValues) {
      if (!choices.empty()) choices += '|';
      choices += name;
    }
    line(key, enum_name(value), fmt::format("{}{}[{}]", doc, *doc ? " " : "", choices).c_str());
  }

 private:
  void comment(const char* doc) {
    if (*doc) out_ << std::string(static_cast<std::size_t>(indent_), ' ') << "# " << doc << '\n';
  }
  void line(const char* key, const std::string& value, const char* doc) {
    out_ << std::string(static_cast<std::size_t>(indent_), ' ') << key << ": " << value;
    if (*doc) out_ << "  # " << doc;
    out_ << '\n';
  }
  std::ostringstream& out_;
  int indent_;
};

// --- reference documentation ---------------------------------------------------------------------

class Documenter {
 public:
  Documenter(std::ostringstream& out, std::string prefix) : out_(out), prefix_(std::move(prefix)) {}

  template <class T>
  void field(const char* key, const T& v, const char* doc) {
    std::ostringstream value;
    Writer writer(value);
    writer.field("x", v, "");
    std::string text = value.str().substr(3);
    if (!text.empty() && text.back() == '\n') text.pop_back();
    row(key, text, doc);
  }
  template <class S>
  void section(const char* key, S& sub, const char* doc) {
    Documenter nested(out_, prefix_ + key + ".");
    if (*doc) out_ << "| `" << prefix_ << key << "` | (section) | " << escape(doc) << " |\n";
    visit(nested, sub);
  }
  template <class E>
  void choice(const char* key, E value, const char* doc) {
    std::string choices;
    for (const auto& [v, name] : EnumNames<E>::kValues) {
      choices += (choices.empty() ? "" : ", ") + std::string(name);
    }
    row(key, enum_name(value), fmt::format("{}{}one of: {}", doc, *doc ? "; " : "", choices));
  }

 private:
  static std::string escape(std::string s) {
    std::string out;
    for (char c : s) out += (c == '|') ? std::string("\\|") : std::string(1, c);
    return out;
  }
  void row(const char* key, const std::string& value, const std::string& doc) {
    out_ << "| `" << prefix_ << key << "` | `" << escape(value) << "` | " << escape(doc) << " |\n";
  }
  std::ostringstream& out_;
  std::string prefix_;
};

}  // namespace

namespace {

/// A validation error of the settings in `file`, with the file and, when the message names a
/// key the file holds, its line ("run.yaml:7: configuration key 'tracking.orb.scale_factor':
/// ..."). A key left at its default has no line.
ConfigError located(const YamlFile& file, const ConfigError& error) {
  const std::string key = error.key();
  const int line = key.empty() ? 0 : file.line_of_path(key);
  return ConfigError(line > 0 ? fmt::format("{}:{}: {}", file.source(), line, error.what())
                              : fmt::format("{}: {}", file.source(), error.what()));
}

pipeline::SystemConfig read_system_config(const YamlFile& file) {
  pipeline::SystemConfig config;
  Reader reader(file.root());
  visit(reader, config);
  file.check_all_keys_used();
  try {
    config.validate();
  } catch (const ConfigError& e) {
    throw located(file, e);
  }
  return config;
}

}  // namespace

pipeline::SystemConfig parse_system_config(const std::string& yaml,
                                           const std::string& source_name) {
  return read_system_config(YamlFile::parse(yaml, source_name));
}

pipeline::SystemConfig load_system_config(const std::string& path) {
  return read_system_config(YamlFile::load(path));
}

std::string system_config_to_yaml(const pipeline::SystemConfig& config) {
  std::ostringstream out;
  out << "# DDL-SLAM settings (every key: docs/configuration.md). Read with --config.\n";
  pipeline::SystemConfig copy = config;
  Writer writer(out);
  visit(writer, copy);
  return out.str();
}

std::string system_config_reference_markdown() {
  std::ostringstream out;
  out << "| key | default | meaning |\n|---|---|---|\n";
  pipeline::SystemConfig defaults;
  Documenter doc(out, "");
  visit(doc, defaults);
  return out.str();
}

pipeline::RunMode parse_run_mode(const std::string& text, const std::string& key) {
  return enum_value<pipeline::RunMode>(text, key);
}

segmentation::Backend parse_segmentation_backend(const std::string& text, const std::string& key) {
  return enum_value<segmentation::Backend>(text, key);
}

std::string default_vocabulary_path() { return DDL_DEFAULT_VOCABULARY; }

}  // namespace ddl::config
