#include "ddl/io/dataset_factory.h"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include "config_error_check.h"
#include "ddl/core/error.h"
#include "ddl/io/bonn_dataset.h"
#include "test_sequence.h"

namespace ddl::io {
namespace {

using test::TempDir;
using ::testing::HasSubstr;

TEST(DatasetFactory, DetectsKindFromFolderName) {
  EXPECT_EQ(detect_dataset_kind("/data/rgbd_bonn_balloon"), DatasetKind::kBonn);
  EXPECT_EQ(detect_dataset_kind("/data/rgbd_bonn_person_tracking2/"), DatasetKind::kBonn);
  EXPECT_EQ(detect_dataset_kind("/data/rgbd_dataset_freiburg3_walking_xyz"), DatasetKind::kTum);
  EXPECT_EQ(detect_dataset_kind("/data/my_bonn_copy"), DatasetKind::kTum);
  EXPECT_EQ(parse_dataset_kind("bonn"), DatasetKind::kBonn);
  EXPECT_EQ(to_string(DatasetKind::kAuto), "auto");
  EXPECT_TRUE(test_support::throws_config_error_for_key([] { parse_dataset_kind("kitti"); },
                                                        "dataset.kind"));
  EXPECT_TRUE(
      test_support::throws_config_error_naming([] { parse_dataset_kind("kitti"); }, "'kitti'"));
}

TEST(DatasetFactory, DefaultCameraFromFolderName) {
  const auto default_for = [](const std::string& name, DatasetKind kind = DatasetKind::kAuto) {
    TempDir dir(name);
    return default_camera_for(dir.path() + "/", kind);
  };
  EXPECT_EQ(default_for("rgbd_dataset_freiburg1_rpy"), "tum1");
  EXPECT_EQ(default_for("rgbd_dataset_freiburg2_desk_with_person"), "tum2");
  EXPECT_EQ(default_for("rgbd_dataset_freiburg3_walking_xyz"), "tum3");
  EXPECT_EQ(default_for("rgbd_bonn_crowd"), "bonn");
  EXPECT_EQ(default_for("renamed_sequence", DatasetKind::kBonn), "bonn");
  try {
    default_camera_for("/nonexistent/rgbd_dataset_freiburg1_rpy");
    ADD_FAILURE() << "no error for a missing folder";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(),
                HasSubstr("/nonexistent/rgbd_dataset_freiburg1_rpy: sequence folder not found"));
  }
}

TEST(DatasetFactory, DefaultCameraFromCameraYamlOrError) {
  TempDir dir("my_sequence");
  try {
    default_camera_for(dir.path());
    ADD_FAILURE() << "no error for a folder without a known name or camera.yaml";
  } catch (const InputError& e) {
    EXPECT_THAT(e.what(), HasSubstr(dir.path()));
    EXPECT_THAT(e.what(), HasSubstr("pass --camera"));
  }
  dir.write("camera.yaml", "camera: {}\n");
  EXPECT_EQ(default_camera_for(dir.path()), dir.file("camera.yaml"));
}

TEST(DatasetFactory, OpensTumAndBonnReaders) {
  TempDir tum("rgbd_dataset_freiburg3_crafted");
  test::write_sequence(tum, 3);
  TempDir bonn("rgbd_bonn_crafted");
  test::write_sequence(bonn, 4);

  DatasetOptions options;
  options.camera = test::tiny_camera();
  const auto tum_reader = open_dataset(tum.path(), options);
  EXPECT_EQ(tum_reader->size(), 3u);
  EXPECT_EQ(dynamic_cast<const BonnDataset*>(tum_reader.get()), nullptr);
  EXPECT_EQ(tum_reader->name(), "rgbd_dataset_freiburg3_crafted");

  const auto bonn_reader = open_dataset(bonn.path(), options);
  EXPECT_EQ(bonn_reader->size(), 4u);
  EXPECT_NE(dynamic_cast<const BonnDataset*>(bonn_reader.get()), nullptr);

  options.kind = DatasetKind::kTum;  // explicit kind wins over the folder name
  EXPECT_EQ(dynamic_cast<const BonnDataset*>(open_dataset(bonn.path(), options).get()), nullptr);

  options.sequence.max_difference_s = 0.001;  // tighter than the 3 ms RGB/depth offset
  EXPECT_THROW(open_dataset(tum.path(), options), InputError);
}

TEST(DatasetFactory, CameraIsRequired) {
  TempDir dir("rgbd_dataset_freiburg1_crafted");
  test::write_sequence(dir, 2);
  EXPECT_TRUE(test_support::throws_config_error_naming(
      [&] { open_dataset(dir.path(), DatasetOptions{}); }, "no camera given"));
}

}  // namespace
}  // namespace ddl::io
