#include "ddl/config/dataset_config.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <filesystem>
#include <string>

#include "../io/test_sequence.h"
#include "config_test_util.h"
#include "ddl/core/error.h"
#include "ddl/io/dataset_factory.h"

namespace ddl::config {
namespace {

using test::error_of;
using test::ScopedEnv;
using test::TempDir;
using ::testing::HasSubstr;

TEST(DatasetCamera, ChosenFromFolderOrArgument) {
  ScopedEnv no_override("DDL_CONFIG_DIR", std::nullopt);
  TempDir fr2("rgbd_dataset_freiburg2_xyz");
  EXPECT_EQ(resolve_dataset_camera(fr2.path(), "").name, "tum2");
  TempDir bonn("rgbd_bonn_balloon");
  EXPECT_EQ(resolve_dataset_camera(bonn.path(), "").name, "bonn");
  EXPECT_EQ(resolve_dataset_camera(bonn.path(), "tum3").name, "tum3");

  TempDir dir("own_sequence");
  EXPECT_THAT(error_of<InputError>([&] { resolve_dataset_camera(dir.path(), ""); }),
              HasSubstr("pass --camera"));
  dir.write("camera.yaml",
            "camera: {name: test, width: 64, height: 48, fx: 50, fy: 50, cx: 32, cy: 24, "
            "depth_factor: 5000}\n");
  EXPECT_EQ(resolve_dataset_camera(dir.path(), "").name, "test");
}

TEST(DatasetCamera, OpensRealFr1RpyWithItsDefaultCamera) {
  const std::string dir = test::shared_dir() + "/data/tum/rgbd_dataset_freiburg1_rpy";
  if (!std::filesystem::exists(dir + "/rgb.txt")) {
    GTEST_SKIP() << "TUM fr1_rpy not found at " << dir << " (set DDL_SHARED_DIR)";
  }
  ScopedEnv no_override("DDL_CONFIG_DIR", std::nullopt);
  io::DatasetOptions options;
  options.camera = resolve_dataset_camera(dir, "");
  EXPECT_EQ(options.camera->name, "tum1");
  const auto reader = io::open_dataset(dir, options);
  EXPECT_EQ(reader->size(), 694u);
  EXPECT_EQ(reader->camera().fx, 517.306408);
  EXPECT_FALSE(reader->camera().has_distortion());
}

TEST(DatasetConfig, ReadsDatasetSection) {
  const YamlFile file = YamlFile::parse(
      "dataset:\n"
      "  kind: bonn\n"
      "  associations: timestamps\n"
      "  max_difference: 0.01\n"
      "  check_files: false\n",
      "run.yaml");
  const io::DatasetOptions options = read_dataset_options(file.root().get_map("dataset"));
  file.check_all_keys_used();
  EXPECT_EQ(options.kind, io::DatasetKind::kBonn);
  EXPECT_EQ(options.sequence.association, io::AssociationSource::kTimestamps);
  EXPECT_EQ(options.sequence.max_difference_s, 0.01);
  EXPECT_FALSE(options.sequence.check_files_on_open);
  EXPECT_FALSE(options.camera.has_value());

  // Absent keys keep the defaults given.
  io::DatasetOptions defaults;
  defaults.sequence.max_difference_s = 0.03;
  const YamlFile empty = YamlFile::parse("dataset: {}\n", "empty.yaml");
  EXPECT_EQ(
      read_dataset_options(empty.root().get_map("dataset"), defaults).sequence.max_difference_s,
      0.03);
}

TEST(DatasetConfig, BadDatasetValuesNameFileAndKey) {
  const YamlFile kind = YamlFile::parse("dataset:\n  kind: kitti\n", "k.yaml");
  EXPECT_EQ(error_of<ConfigError>([&] { read_dataset_options(kind.root().get_map("dataset")); }),
            "k.yaml:2: dataset.kind: 'kitti' is not one of auto, tum, bonn");
  const YamlFile diff = YamlFile::parse("dataset:\n  max_difference: -1\n", "d.yaml");
  const std::string msg =
      error_of<ConfigError>([&] { read_dataset_options(diff.root().get_map("dataset")); });
  EXPECT_THAT(msg, HasSubstr("d.yaml"));
  EXPECT_THAT(msg, HasSubstr("dataset.max_difference"));
  const YamlFile typo = YamlFile::parse("dataset:\n  max_diference: 0.01\n", "t.yaml");
  read_dataset_options(typo.root().get_map("dataset"));
  EXPECT_EQ(error_of<ConfigError>([&] { typo.check_all_keys_used(); }),
            "unknown key 'dataset.max_diference' in t.yaml (line 2); did you mean "
            "'dataset.max_difference'?");
}

}  // namespace
}  // namespace ddl::config
