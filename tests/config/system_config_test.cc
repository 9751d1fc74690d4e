#include "ddl/config/system_config.h"

#include <gtest/gtest.h>

#include <functional>
#include <string>

#include "ddl/core/error.h"

namespace ddl::config {
namespace {

std::string message_of(const std::function<void()>& f) {
  try {
    f();
  } catch (const std::exception& e) {
    return e.what();
  }
  return "";
}

TEST(SystemConfig, DefaultsRoundTripThroughYaml) {
  pipeline::SystemConfig defaults;
  const std::string yaml = system_config_to_yaml(defaults);
  const pipeline::SystemConfig back = parse_system_config(yaml, "defaults.yaml");
  EXPECT_EQ(system_config_to_yaml(back), yaml);
}

TEST(SystemConfig, ValuesAreReadIntoTheStructs) {
  const auto config = parse_system_config(
      "mode: threaded\n"
      "tracking:\n"
      "  orb:\n"
      "    num_features: 1500\n"
      "  matching:\n"
      "    reference_bow_ratio: 0.6\n"
      "dynamic:\n"
      "  enabled: false\n"
      "  segmentation:\n"
      "    backend: none\n"
      "    dynamic_classes: [person, dog]\n"
      "  geometry:\n"
      "    growth_veto: any_unrefuted\n"
      "dense:\n"
      "  octree:\n"
      "    resolution_m: 0.1\n",
      "settings.yaml");
  EXPECT_EQ(config.mode, pipeline::RunMode::kThreaded);
  EXPECT_EQ(config.tracking.orb.num_features, 1500);
  EXPECT_FLOAT_EQ(config.tracking.matching.reference_bow_ratio, 0.6f);
  EXPECT_FALSE(config.dynamic.enabled);
  EXPECT_EQ(config.dynamic.segmentation.backend, segmentation::Backend::kNone);
  EXPECT_EQ(config.dynamic.segmentation.dynamic_classes,
            (std::vector<std::string>{"person", "dog"}));
  EXPECT_EQ(config.dynamic.geometry.growth_veto, dynamics::GrowthVeto::kAnyUnrefuted);
  EXPECT_DOUBLE_EQ(config.dense.octree.resolution_m, 0.1);
  // Untouched keys keep their defaults.
  EXPECT_EQ(config.tracking.orb.num_levels, 8);
}

TEST(SystemConfig, UnknownKeyNamesFileLineAndKey) {
  const std::string msg = message_of(
      [] { parse_system_config("tracking:\n  orb:\n    num_featurs: 10\n", "typo.yaml"); });
  EXPECT_NE(msg.find("typo.yaml"), std::string::npos) << msg;
  EXPECT_NE(msg.find("tracking.orb.num_featurs"), std::string::npos) << msg;
  EXPECT_NE(msg.find("3"), std::string::npos) << msg;
}

TEST(SystemConfig, InvalidValueNamesTheKey) {
  const std::string msg = message_of(
      [] { parse_system_config("tracking:\n  orb:\n    num_features: -5\n", "bad.yaml"); });
  EXPECT_NE(msg.find("orb.num_features"), std::string::npos) << msg;
  const std::string enum_msg = message_of([] { parse_system_config("mode: fast\n", "bad.yaml"); });
  EXPECT_NE(enum_msg.find("mode"), std::string::npos) << enum_msg;
  EXPECT_NE(enum_msg.find("deterministic"), std::string::npos) << enum_msg;
  const std::string veto_msg = message_of(
      [] { parse_system_config("dynamic:\n  geometry:\n    growth_veto: some\n", "bad.yaml"); });
  EXPECT_NE(veto_msg.find("dynamic.geometry.growth_veto"), std::string::npos) << veto_msg;
  EXPECT_NE(veto_msg.find("'some'"), std::string::npos) << veto_msg;
  EXPECT_NE(veto_msg.find("any_unrefuted"), std::string::npos) << veto_msg;
  const std::string type_msg =
      message_of([] { parse_system_config("keyframe_queue_capacity: lots\n", "bad.yaml"); });
  EXPECT_NE(type_msg.find("keyframe_queue_capacity"), std::string::npos) << type_msg;
}

// Review finding (stop 20): a value out of range named the key but not its line, although
// unknown keys and type errors did; a second YAML document in the file was silently ignored.
TEST(SystemConfig, ValueOutOfRangeNamesFileLineAndKey) {
  const std::string msg = message_of([] {
    parse_system_config("mode: deterministic\ntracking:\n  orb:\n    scale_factor: .nan\n",
                        "nan.yaml");
  });
  EXPECT_EQ(msg.rfind("nan.yaml:4: ", 0), 0u) << msg;
  EXPECT_NE(msg.find("tracking.orb.scale_factor"), std::string::npos) << msg;
  // A check across keys names one the file does not hold: file, no line.
  const std::string cross =
      message_of([] { parse_system_config("tracking:\n  frame:\n    bf: 50\n", "bf.yaml"); });
  EXPECT_EQ(cross.rfind("bf.yaml: ", 0), 0u) << cross;
  // Segmentation threads go to cv::setNumThreads, which crashed on 2e9 (TBB).
  const std::string threads = message_of([] {
    parse_system_config("dynamic:\n  segmentation:\n    num_threads: 2000000000\n", "t.yaml");
  });
  EXPECT_EQ(threads.rfind("t.yaml:3: ", 0), 0u) << threads;
  EXPECT_NE(threads.find("dynamic.segmentation.num_threads"), std::string::npos) << threads;
  // 2 * dilation_px + 1 overflowed an int in the geometry check.
  const std::string dilation = message_of([] {
    parse_system_config("dynamic:\n  use_geometry: true\n  geometry:\n    dilation_px: 100000\n",
                        "d.yaml");
  });
  EXPECT_NE(dilation.find("dynamic.geometry.dilation_px"), std::string::npos) << dilation;
}

TEST(SystemConfig, MoreThanOneYamlDocumentIsAnError) {
  const std::string msg = message_of(
      [] { parse_system_config("mode: deterministic\n---\nmode: threaded\n", "two.yaml"); });
  EXPECT_NE(msg.find("two.yaml"), std::string::npos) << msg;
  EXPECT_NE(msg.find("2 YAML documents"), std::string::npos) << msg;
  // One document with a leading marker, and an empty file, are fine.
  EXPECT_NO_THROW(parse_system_config("---\nmode: threaded\n", "one.yaml"));
  EXPECT_NO_THROW(parse_system_config("", "empty.yaml"));
}

// The virtual baseline of the RGB-D residuals is one number in three sections: a file that sets
// only one of them is rejected (mapping and loop closing predicted the stored u_r with another bf,
// off by delta_bf / z pixels, found by review on 2026-11-26).
TEST(SystemConfig, TheThreeBfKeysMustAgree) {
  const std::string msg =
      message_of([] { parse_system_config("tracking:\n  frame:\n    bf: 50\n", "bf.yaml"); });
  EXPECT_NE(msg.find("'mapping.bf'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("tracking.frame.bf"), std::string::npos) << msg;
  EXPECT_NO_THROW(parse_system_config(
      "tracking:\n  frame:\n    bf: 50\nmapping:\n  bf: 50\nloop:\n  bf: 50\n", "bf.yaml"));
}

// BoW matching compares direct-index node ids: keyframes whose bag of words mapping computed at
// another depth than tracking's would share no node with any frame (review, stop 26).
TEST(SystemConfig, TheTwoBowLevelsUpKeysMustAgree) {
  const std::string msg = message_of(
      [] { parse_system_config("tracking:\n  frame:\n    bow_levels_up: 4\n", "bow.yaml"); });
  EXPECT_NE(msg.find("'mapping.bow_levels_up'"), std::string::npos) << msg;
  EXPECT_NE(msg.find("tracking.frame.bow_levels_up"), std::string::npos) << msg;
  EXPECT_NO_THROW(parse_system_config(
      "tracking:\n  frame:\n    bow_levels_up: 4\nmapping:\n  bow_levels_up: 4\n", "bow.yaml"));
}

TEST(SystemConfig, ReferenceListsEveryNestedKey) {
  const std::string md = system_config_reference_markdown();
  for (const char* key :
       {"`mode`", "`tracking.orb.num_features`", "`mapping.local_ba`", "`loop.enabled`",
        "`dynamic.geometry.max_parallax_deg`", "`dense.inpainting.num_keyframes`",
        "`dense.octree.resolution_m`", "`dynamic.segmentation.dynamic_classes`"}) {
    EXPECT_NE(md.find(key), std::string::npos) << key;
  }
}

}  // namespace
}  // namespace ddl::config
