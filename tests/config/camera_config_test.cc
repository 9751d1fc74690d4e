#include "ddl/config/camera_config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>

#include "../io/test_sequence.h"
#include "config_test_util.h"
#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/error.h"

namespace ddl::config {
namespace {

using test::error_of;
using test::ScopedEnv;
using test::TempDir;
using ::testing::HasSubstr;

std::string read_file(const std::string& path) {
  std::ifstream file(path, std::ios::binary);
  std::ostringstream text;
  text << file.rdbuf();
  return text.str();
}

const char* kValid =
    "camera:\n"                                        // 1
    "  name: test\n"                                   // 2
    "  width: 640\n"                                   // 3
    "  height: 480\n"                                  // 4
    "  fx: 500.0\n"                                    // 5
    "  fy: 501.0\n"                                    // 6
    "  cx: 320.0\n"                                    // 7
    "  cy: 240.0\n"                                    // 8
    "  distortion: [0.1, -0.2, 0.001, 0.002, 0.05]\n"  // 9
    "  depth_factor: 1000.0\n"                         // 10
    "  fps: 15\n";                                     // 11

std::string replaced(std::string text, const std::string& from, const std::string& to) {
  text.replace(text.find(from), from.size(), to);
  return text;
}

// ----------------------------------------------------------------------------------------------

TEST(CameraConfig, BuiltinCamerasMatchPublishedCalibrations) {
  ScopedEnv no_override("DDL_CONFIG_DIR", std::nullopt);
  EXPECT_EQ(builtin_camera_names(),
            (std::vector<std::string>{"tum1", "tum2", "tum3", "bonn", "synthetic"}));
  struct Expected {
    const char* name;
    double fx, fy, cx, cy;
    std::array<double, 5> d;
  };
  const Expected expected[] = {
      {"tum1",
       517.306408,
       516.469215,
       318.643040,
       255.313989,
       {0.262383, -0.953104, -0.005358, 0.002628, 1.163314}},
      {"tum2",
       520.908620,
       521.007327,
       325.141442,
       249.701764,
       {0.231222, -0.784899, -0.003257, -0.000105, 0.917205}},
      {"tum3", 535.4, 539.2, 320.1, 247.6, {0, 0, 0, 0, 0}},
      {"bonn",
       542.822841,
       542.576870,
       315.593520,
       237.756098,
       {0.039903, -0.099343, -0.000730, -0.000144, 0.0}},
      {"synthetic", 535.4, 539.2, 320.1, 247.6, {0, 0, 0, 0, 0}},
  };
  for (const Expected& e : expected) {
    SCOPED_TRACE(e.name);
    const camera::PinholeCamera c = load_camera(e.name);
    EXPECT_EQ(c.name, e.name);
    EXPECT_EQ(c.width, 640);
    EXPECT_EQ(c.height, 480);
    EXPECT_EQ(c.fx, e.fx);
    EXPECT_EQ(c.fy, e.fy);
    EXPECT_EQ(c.cx, e.cx);
    EXPECT_EQ(c.cy, e.cy);
    EXPECT_EQ(c.distortion, e.d);
    EXPECT_EQ(c.depth_factor, 5000.0);  // tum2 included: see the note in tum2.yaml
    EXPECT_EQ(c.fps, 30.0);
    // Only fr1's depth timing was measured (docs/dynamics.md, "Depth in time").
    if (std::string(e.name) == "tum1") {
      EXPECT_EQ(c.depth_time_offset_s, std::optional<double>(-0.020));
    } else {
      EXPECT_FALSE(c.depth_time_offset_s.has_value());
    }
  }
}

TEST(CameraConfig, EmbeddedBuiltinsEqualTheRepositoryFiles) {
  ScopedEnv no_override("DDL_CONFIG_DIR", std::nullopt);
  for (const std::string& name : builtin_camera_names()) {
    const std::string path = std::string(DDL_SOURCE_DIR) + "/config/cameras/" + name + ".yaml";
    EXPECT_EQ(embedded_camera_yaml(name), read_file(path)) << path << " changed: rebuild";
    EXPECT_EQ(builtin_camera_source(name), path);
    // The embedded copy parses to the same camera.
    const camera::PinholeCamera a = parse_camera(std::string(embedded_camera_yaml(name)), name);
    const camera::PinholeCamera b = load_camera(name);
    EXPECT_EQ(camera_to_yaml(a), camera_to_yaml(b));
  }
}

TEST(CameraConfig, ConfigDirOverride) {
  TempDir dir("config");
  dir.write("cameras/tum1.yaml", replaced(kValid, "name: test", "name: tum1_override"));
  {
    ScopedEnv env("DDL_CONFIG_DIR", dir.path());
    EXPECT_EQ(load_camera("tum1").name, "tum1_override");
    EXPECT_EQ(builtin_camera_source("tum1"), dir.file("cameras/tum1.yaml"));
    // An explicit override never falls back silently.
    const std::string msg = error_of<InputError>([] { load_camera("tum2"); });
    EXPECT_THAT(msg, HasSubstr(dir.file("cameras/tum2.yaml")));
    EXPECT_THAT(msg, HasSubstr("DDL_CONFIG_DIR"));
  }
  EXPECT_EQ(load_camera("tum1").name, "tum1");
}

TEST(CameraConfig, LoadsFileAndRoundTripsThroughYaml) {
  TempDir dir("cams");
  dir.write("mine.yaml", kValid);
  const camera::PinholeCamera c = load_camera(dir.file("mine.yaml"));
  EXPECT_EQ(c.name, "test");
  EXPECT_EQ(c.fx, 500.0);
  EXPECT_EQ(c.distortion[4], 0.05);
  EXPECT_EQ(c.depth_factor, 1000.0);
  EXPECT_EQ(c.fps, 15.0);

  camera::PinholeCamera odd = c;
  odd.name = "odd \"quoted\" name: x\\y\nz # not a comment";
  odd.fx = 1.0 / 3.0 * 1000.0;
  odd.cy = 239.123456789012345;
  odd.distortion = {1e-7, -0.1 / 3.0, 0.0, -2.5e-5, 1.0 / 7.0};
  const camera::PinholeCamera back = parse_camera(camera_to_yaml(odd), "written.yaml");
  EXPECT_EQ(back.name, odd.name);
  EXPECT_EQ(back.fx, odd.fx);
  EXPECT_EQ(back.cy, odd.cy);
  EXPECT_EQ(back.distortion, odd.distortion);
  EXPECT_EQ(camera_to_yaml(back), camera_to_yaml(odd));
  EXPECT_FALSE(back.depth_time_offset_s.has_value());  // absent: synchronised
  odd.depth_time_offset_s = -0.0175;
  const camera::PinholeCamera timed = parse_camera(camera_to_yaml(odd), "timed.yaml");
  EXPECT_EQ(timed.depth_time_offset_s, odd.depth_time_offset_s);

  // Optional keys: name defaults to the file name, distortion to none, fps to 30.
  dir.write(
      "minimal.yaml",
      "camera: {width: 64, height: 48, fx: 50, fy: 50, cx: 32, cy: 24, depth_factor: 5000}\n");
  const camera::PinholeCamera minimal = load_camera(dir.file("minimal.yaml"));
  EXPECT_EQ(minimal.name, "minimal");
  EXPECT_FALSE(minimal.has_distortion());
  EXPECT_EQ(minimal.fps, 30.0);
}

TEST(CameraConfig, UnknownKeyNamesKeyFileAndSuggestion) {
  TempDir dir("cams");
  dir.write("typo.yaml", replaced(kValid, "  fx: 500.0", "  fxx: 500.0"));
  // fx is then missing, which is reported first (required keys are read before the check).
  EXPECT_EQ(error_of<ConfigError>([&] { load_camera(dir.file("typo.yaml")); }),
            dir.file("typo.yaml") +
                ":2: missing required key 'camera.fx' (a number); is 'camera.fxx' on line 5 a "
                "typo?");

  dir.write("extra.yaml", replaced(kValid, "  fps: 15\n", "  fps: 15\n  fxx: 1\n"));
  EXPECT_EQ(error_of<ConfigError>([&] { load_camera(dir.file("extra.yaml")); }),
            "unknown key 'camera.fxx' in " + dir.file("extra.yaml") + " (line 12)");

  // A misspelt optional key would silently keep its default without this check.
  dir.write("fps.yaml", replaced(kValid, "  fps: 15", "  fsp: 15"));
  EXPECT_EQ(error_of<ConfigError>([&] { load_camera(dir.file("fps.yaml")); }),
            "unknown key 'camera.fsp' in " + dir.file("fps.yaml") +
                " (line 11); did you mean 'camera.fps'?");

  dir.write("top.yaml", std::string(kValid) + "camera_model: pinhole\n");
  EXPECT_EQ(error_of<ConfigError>([&] { load_camera(dir.file("top.yaml")); }),
            "unknown key 'camera_model' in " + dir.file("top.yaml") + " (line 12)");
}

TEST(CameraConfig, InvalidValuesNameFileAndKey) {
  TempDir dir("cams");
  dir.write("negative.yaml", replaced(kValid, "fx: 500.0", "fx: -500.0"));
  std::string msg = error_of<ConfigError>([&] { load_camera(dir.file("negative.yaml")); });
  EXPECT_THAT(msg, HasSubstr(dir.file("negative.yaml")));
  EXPECT_THAT(msg, HasSubstr("camera.fx"));
  EXPECT_THAT(msg, HasSubstr("must be a positive focal length (got -500)"));

  dir.write("late.yaml",
            replaced(kValid, "  fps: 15\n", "  fps: 15\n  depth_time_offset_s: 0.5\n"));
  msg = error_of<ConfigError>([&] { load_camera(dir.file("late.yaml")); });
  EXPECT_THAT(msg, HasSubstr(dir.file("late.yaml")));
  EXPECT_THAT(msg, HasSubstr("camera.depth_time_offset_s"));
  EXPECT_THAT(msg, HasSubstr("must be in -0.1..0.1 seconds"));

  dir.write("text.yaml", replaced(kValid, "fx: 500.0", "fx: abc"));
  EXPECT_EQ(error_of<ConfigError>([&] { load_camera(dir.file("text.yaml")); }),
            dir.file("text.yaml") + ":5: camera.fx: expected a number, got 'abc'");

  dir.write("width.yaml", replaced(kValid, "width: 640", "width: 640.5"));
  EXPECT_EQ(error_of<ConfigError>([&] { load_camera(dir.file("width.yaml")); }),
            dir.file("width.yaml") + ":3: camera.width: expected an integer, got '640.5'");

  dir.write("short.yaml",
            replaced(kValid, "[0.1, -0.2, 0.001, 0.002, 0.05]", "[0.1, -0.2, 0.001, 0.002]"));
  EXPECT_EQ(error_of<ConfigError>([&] { load_camera(dir.file("short.yaml")); }),
            dir.file("short.yaml") + ":9: camera.distortion: expected a list of 5 numbers, got 4");

  dir.write("item.yaml", replaced(kValid, "0.001, 0.002", "0.001, x"));
  EXPECT_THAT(error_of<ConfigError>([&] { load_camera(dir.file("item.yaml")); }),
              HasSubstr("camera.distortion[3]: expected a number, got 'x'"));

  dir.write("cx.yaml", replaced(kValid, "cx: 320.0", "cx: 700.0"));
  EXPECT_THAT(error_of<ConfigError>([&] { load_camera(dir.file("cx.yaml")); }),
              HasSubstr("camera.cx': must lie inside the image (got 700)"));

  dir.write("zero_depth.yaml", replaced(kValid, "depth_factor: 1000.0", "depth_factor: 0"));
  EXPECT_THAT(error_of<ConfigError>([&] { load_camera(dir.file("zero_depth.yaml")); }),
              HasSubstr("camera.depth_factor"));

  // Values no camera has (review, stop 24): they ran with nothing tracked and exit code 0.
  dir.write("tiny_depth.yaml", replaced(kValid, "depth_factor: 1000.0", "depth_factor: 1e-300"));
  EXPECT_THAT(error_of<ConfigError>([&] { load_camera(dir.file("tiny_depth.yaml")); }),
              HasSubstr("camera.depth_factor"));
  for (const char* fx : {"fx: 1e300", "fx: 1e-9"}) {
    dir.write("fx.yaml", replaced(kValid, "fx: 500.0", fx));
    EXPECT_THAT(error_of<ConfigError>([&] { load_camera(dir.file("fx.yaml")); }),
                HasSubstr(dir.file("fx.yaml") + ":5: configuration key 'camera.fx': gives a "
                                                "horizontal field of view"))
        << fx;
  }
  dir.write("valid.yaml", kValid);
  dir.write("wild.yaml", replaced(kValid, "[0.1, -0.2, 0.001, 0.002, 0.05]", "[1e6, 0, 0, 0, 0]"));
  EXPECT_THAT(error_of<ConfigError>([&] { load_camera(dir.file("wild.yaml")); }),
              HasSubstr(dir.file("wild.yaml") + ":9: configuration key 'camera.distortion'"));
  // fr1's real coefficients keep nearly all of the image.
  EXPECT_NO_THROW(load_camera("tum1"));
}

TEST(CameraConfig, SyntaxErrorNamesFileAndLine) {
  TempDir dir("cams");
  dir.write("broken.yaml", replaced(kValid, "  cy: 240.0\n", "  cy: [240.0\n"));
  const std::string msg = error_of<ConfigError>([&] { load_camera(dir.file("broken.yaml")); });
  EXPECT_THAT(msg, HasSubstr(dir.file("broken.yaml") + ":"));
  EXPECT_THAT(msg, HasSubstr("YAML syntax error"));

  dir.write("indent.yaml", "camera:\n  fx: 1\n fy: 2\n");
  EXPECT_THAT(error_of<ConfigError>([&] { load_camera(dir.file("indent.yaml")); }),
              HasSubstr(dir.file("indent.yaml") + ":3:"));
}

TEST(CameraConfig, MissingOrUnknownCamera) {
  TempDir dir("cams");
  std::string msg = error_of<InputError>([&] { load_camera(dir.file("absent.yaml")); });
  EXPECT_THAT(msg, HasSubstr(dir.file("absent.yaml")));
  EXPECT_THAT(msg, HasSubstr("camera file not found"));
  msg = error_of<InputError>([] { load_camera("tum4"); });
  EXPECT_THAT(msg, HasSubstr("tum1|tum2|tum3|bonn|synthetic"));

  dir.write("empty.yaml", "# nothing here\n");
  EXPECT_THAT(error_of<ConfigError>([&] { load_camera(dir.file("empty.yaml")); }),
              HasSubstr("missing required key 'camera'"));
}

}  // namespace
}  // namespace ddl::config
