#include "ddl/config/yaml_reader.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "ddl/core/error.h"

namespace ddl::config {
namespace {

using ::testing::HasSubstr;

template <typename Fn>
std::string config_error_of(Fn&& fn) {
  try {
    fn();
  } catch (const ConfigError& e) {
    return e.what();
  } catch (const std::exception& e) {
    ADD_FAILURE() << "expected ddl::ConfigError, got: " << e.what();
    return {};
  }
  ADD_FAILURE() << "expected ddl::ConfigError, nothing was thrown";
  return {};
}

constexpr const char* kText =
    "pipeline:\n"                    // line 1
    "  threaded: true\n"             // 2
    "  tracking:\n"                  // 3
    "    features: 1000\n"           // 4
    "    scale: 1.2\n"               // 5
    "    mode: rgbd\n"               // 6
    "    levels: [1, 2.5, -3e-2]\n"  // 7
    "name: run one\n";               // 8

TEST(YamlReader, ReadsTypedValuesAtDottedPaths) {
  const YamlFile file = YamlFile::parse(kText, "run.yaml");
  const YamlMap pipeline = file.root().get_map("pipeline");
  EXPECT_TRUE(pipeline.get_bool("threaded"));
  const YamlMap tracking = pipeline.get_map("tracking");
  EXPECT_EQ(tracking.path(), "pipeline.tracking");
  EXPECT_EQ(tracking.get_int("features"), 1000);
  EXPECT_DOUBLE_EQ(tracking.get_double("scale"), 1.2);
  EXPECT_DOUBLE_EQ(tracking.get_double("features"), 1000.0);  // an integer is a number
  EXPECT_EQ(tracking.get_choice("mode", {"mono", "rgbd"}), "rgbd");
  EXPECT_EQ(tracking.get_doubles("levels"), (std::vector<double>{1, 2.5, -0.03}));
  EXPECT_EQ(tracking.line_of("scale"), 5);
  double absent = 7.0;
  EXPECT_FALSE(tracking.read("absent", absent));
  EXPECT_EQ(absent, 7.0);
  EXPECT_EQ(file.root().get_string("name"), "run one");
  EXPECT_NO_THROW(file.check_all_keys_used());
}

TEST(YamlReader, WrongTypesNameFileLineAndKey) {
  const YamlFile file = YamlFile::parse(kText, "run.yaml");
  const YamlMap tracking = file.root().get_map("pipeline").get_map("tracking");
  EXPECT_EQ(config_error_of([&] { tracking.get_double("mode"); }),
            "run.yaml:6: pipeline.tracking.mode: expected a number, got 'rgbd'");
  EXPECT_EQ(config_error_of([&] { tracking.get_int("scale"); }),
            "run.yaml:5: pipeline.tracking.scale: expected an integer, got '1.2'");
  EXPECT_THAT(config_error_of([&] { tracking.get_bool("features"); }),
              HasSubstr("pipeline.tracking.features: expected true or false, got '1000'"));
  EXPECT_THAT(config_error_of([&] {
                tracking.get_choice("mode", {"mono", "stereo"});
              }),
              HasSubstr("'rgbd' is not one of mono, stereo"));
  EXPECT_THAT(config_error_of([&] { tracking.get_doubles("levels", 2); }),
              HasSubstr("pipeline.tracking.levels: expected a list of 2 numbers, got 3"));
  EXPECT_THAT(config_error_of([&] { tracking.get_map("scale"); }),
              HasSubstr("pipeline.tracking.scale: expected a map of keys, got '1.2'"));
  EXPECT_THAT(config_error_of([&] { tracking.get_double("missing"); }),
              HasSubstr("missing required key 'pipeline.tracking.missing'"));
}

TEST(YamlReader, UnknownKeysAreErrorsWithSuggestion) {
  const YamlFile file = YamlFile::parse(kText, "run.yaml");
  const YamlMap tracking = file.root().get_map("pipeline").get_map("tracking");
  file.root().get_string("name");
  file.root().get_map("pipeline").get_bool("threaded");
  tracking.get_int("features");
  double scales = 0.0;
  tracking.read("scales", scales);  // a reader asks for "scales"; the file has "scale"
  tracking.get_string("mode");
  tracking.get_doubles("levels");
  EXPECT_EQ(config_error_of([&] { file.check_all_keys_used(); }),
            "unknown key 'pipeline.tracking.scale' in run.yaml (line 5); did you mean "
            "'pipeline.tracking.scales'?");
}

TEST(YamlReader, UnreadTopLevelKeyIsUnknown) {
  const YamlFile file = YamlFile::parse("a: 1\nb: 2\n", "x.yaml");
  file.root().get_int("a");
  EXPECT_EQ(config_error_of([&] { file.check_all_keys_used(); }),
            "unknown key 'b' in x.yaml (line 2)");
}

TEST(YamlReader, DuplicateKeysAreErrors) {
  const YamlFile file = YamlFile::parse("a: 1\nb: 2\na: 3\n", "x.yaml");
  file.root().get_int("a");
  file.root().get_int("b");
  EXPECT_THAT(config_error_of([&] { file.check_all_keys_used(); }),
              HasSubstr("duplicate key 'a' in x.yaml (line 3)"));
}

TEST(YamlReader, SyntaxErrorNamesFileLineAndColumn) {
  const std::string msg =
      config_error_of([] { YamlFile::parse("camera:\n  fx: 1\n  distortion: [1, 2\n", "c.yaml"); });
  EXPECT_THAT(msg, HasSubstr("c.yaml:"));
  EXPECT_THAT(msg, HasSubstr("YAML syntax error"));
  const std::string msg2 = config_error_of([] { YamlFile::parse("a: 1\n b: 2\n", "d.yaml"); });
  EXPECT_THAT(msg2, HasSubstr("d.yaml:2:"));
}

TEST(YamlReader, TopLevelMustBeAMap) {
  EXPECT_THAT(config_error_of([] { YamlFile::parse("- 1\n- 2\n", "l.yaml"); }),
              HasSubstr("l.yaml:1: expected a map of keys at the top level, got a list"));
  const YamlFile empty = YamlFile::parse("", "e.yaml");
  EXPECT_THAT(config_error_of([&] { empty.root().get_map("camera"); }),
              HasSubstr("e.yaml: missing required key 'camera'"));
}

TEST(YamlReader, NumbersAreParsedStrictly) {
  const YamlFile file = YamlFile::parse(
      "a: 1.5e3\nb: .inf\nc: 0x10\nd: 1,5\ne: ''\nf:\ng: -7\nh: 3000000000\n", "n.yaml");
  const YamlMap r = file.root();
  EXPECT_EQ(r.get_double("a"), 1500.0);
  EXPECT_TRUE(std::isinf(r.get_double("b")));
  EXPECT_THROW(r.get_double("c"), ConfigError);
  EXPECT_THROW(r.get_double("d"), ConfigError);
  EXPECT_THROW(r.get_double("e"), ConfigError);
  EXPECT_THAT(config_error_of([&] { r.get_double("f"); }), HasSubstr("got nothing (null)"));
  EXPECT_EQ(r.get_int("g"), -7);
  EXPECT_THROW(r.get_int("h"), ConfigError);  // out of int range
}

}  // namespace
}  // namespace ddl::config
