#pragma once
// Strict YAML reading for configuration files. The only place in the project that reads YAML
// (ARCHITECTURE.md section 4); the rest of the code takes typed structs.
//
// Strictness:
//   - a YAML syntax error names the file, line and column (yaml-cpp's mark);
//   - every value is read with its full dotted key path ("camera.fx") so an error names it, with
//     the file and line: "cam.yaml:4: camera.fx: expected a number, got 'abc'";
//   - a missing required key, a duplicate key, or a key no reader asked for is an error
//     ("unknown key 'camera.fxx' in cam.yaml (line 4); did you mean 'camera.fx'?"): a typo must
//     never silently become a default.
// Errors are ddl::ConfigError; a missing or unreadable file is ddl::InputError.
//
// Use:
//   YamlFile file = YamlFile::load(path);
//   YamlMap camera = file.root().get_map("camera");
//   cam.fx = camera.get_double("fx");           // required
//   camera.read("fps", cam.fps);                // optional, keeps the default when absent
//   file.check_all_keys_used();                 // unknown keys -> error
//
// Threads: a YamlFile and the YamlMaps taken from it share bookkeeping of which keys were asked
// for; use them from one thread at a time.

#include <yaml-cpp/yaml.h>

#include <array>
#include <cstddef>
#include <initializer_list>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <vector>

namespace ddl::config {

namespace detail {
struct YamlContext;
}

/// A YAML map at a dotted key path ("" for the document root).
class YamlMap {
 public:
  /// Dotted path of this map ("camera"), empty for the root.
  const std::string& path() const { return path_; }
  /// The file (or source name) the map was read from.
  const std::string& source() const;
  /// Full dotted path of a key in this map ("camera.fx").
  std::string key_path(const std::string& key) const;

  bool has(const std::string& key) const;
  /// Keys as written, in file order.
  std::vector<std::string> keys() const;
  /// 1-based line of the key's value, 0 when unknown or absent.
  int line_of(const std::string& key) const;

  // Required values: throw ddl::ConfigError naming file, line and key when absent or mistyped.
  double get_double(const std::string& key) const;
  int get_int(const std::string& key) const;
  bool get_bool(const std::string& key) const;
  std::string get_string(const std::string& key) const;
  /// A string that must be one of `choices`.
  std::string get_choice(const std::string& key,
                         std::initializer_list<std::string_view> choices) const;
  /// A list of numbers; `expected_size` 0 accepts any length.
  std::vector<double> get_doubles(const std::string& key, std::size_t expected_size = 0) const;
  /// A list of strings (scalars).
  std::vector<std::string> get_strings(const std::string& key) const;
  YamlMap get_map(const std::string& key) const;

  // Optional values: return false and leave `value` unchanged when the key is absent; throw like
  // the getters when present but invalid.
  bool read(const std::string& key, double& value) const;
  bool read(const std::string& key, int& value) const;
  bool read(const std::string& key, bool& value) const;
  bool read(const std::string& key, std::string& value) const;
  bool read(const std::string& key, std::vector<double>& value) const;
  bool read(const std::string& key, std::vector<std::string>& value) const;
  template <std::size_t N>
  bool read(const std::string& key, std::array<double, N>& value) const {
    if (!has(key)) return false;
    const std::vector<double> v = get_doubles(key, N);
    for (std::size_t i = 0; i < N; ++i) value[i] = v[i];
    return true;
  }
  bool read_choice(const std::string& key, std::string& value,
                   std::initializer_list<std::string_view> choices) const;
  std::optional<YamlMap> find_map(const std::string& key) const;

  /// Throws ddl::ConfigError naming file, line and key (for checks the getters cannot express,
  /// e.g. a value out of range).
  [[noreturn]] void fail(const std::string& key, const std::string& what) const;

 private:
  friend class YamlFile;
  YamlMap(std::shared_ptr<detail::YamlContext> context, YAML::Node node, std::string path);
  YAML::Node value_node(const std::string& key) const;  // records the key as asked
  YAML::Node required(const std::string& key, const char* expected) const;

  std::shared_ptr<detail::YamlContext> context_;
  YAML::Node node_;
  std::string path_;
};

/// A parsed YAML document plus the bookkeeping that makes unknown keys errors.
class YamlFile {
 public:
  /// Throws ddl::InputError when the file is missing or unreadable, ddl::ConfigError on a YAML
  /// syntax error (with line and column) or when the top level is not a map.
  static YamlFile load(const std::string& path);
  /// Parses `text`; `source_name` stands for the file name in messages.
  static YamlFile parse(const std::string& text, const std::string& source_name);

  const std::string& source() const;
  YamlMap root() const;
  /// 1-based line of the value at a dotted key path ("tracking.orb.scale_factor"), 0 when the
  /// document does not hold it. Does not count as reading the key.
  int line_of_path(const std::string& dotted_key) const;
  /// Throws ddl::ConfigError for the first key (in file order) that no reader asked for, and for
  /// duplicate keys, in the root and in every map that was opened with get_map/find_map.
  void check_all_keys_used() const;

 private:
  explicit YamlFile(std::shared_ptr<detail::YamlContext> context);
  std::shared_ptr<detail::YamlContext> context_;
};

}  // namespace ddl::config
