#include "ddl/octomap/octree_map.h"

#include <gtest/gtest.h>
#include <octomap/AbstractOcTree.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <filesystem>
#include <memory>

#include "ddl/core/error.h"

namespace ddl::octomap {
namespace {
namespace fs = std::filesystem;

camera::PinholeCamera test_camera() {
  camera::PinholeCamera c;
  c.fx = 535.4;
  c.fy = 539.2;
  c.cx = 320.1;
  c.cy = 247.6;
  return c;
}

// A camera at the origin looking along world +z at a wall z = 3; optionally a person-sized box
// at z = 1.5 covering x in [-0.3, 0.3], y in [-0.8, 0.8].
KeyframeScan wall_scan(bool with_person, std::uint64_t id) {
  const auto cam = test_camera();
  KeyframeScan scan;
  scan.keyframe_id = id;
  scan.bgr = cv::Mat(cam.height, cam.width, CV_8UC3, cv::Scalar(200, 100, 50));
  scan.depth_m = cv::Mat(cam.height, cam.width, CV_32FC1, cv::Scalar(3.0f));
  if (with_person) {
    for (int v = 0; v < cam.height; ++v) {
      for (int u = 0; u < cam.width; ++u) {
        const Vec3d ray = cam.unproject(u, v, 1.5);
        if (std::abs(ray.x()) <= 0.3 && std::abs(ray.y()) <= 0.8) {
          scan.depth_m.at<float>(v, u) = 1.5f;
          scan.bgr.at<cv::Vec3b>(v, u) = {0, 0, 255};
        }
      }
    }
  }
  return scan;
}

bool occupied(const ::octomap::OcTree& tree, double x, double y, double z) {
  const auto* node = tree.search(x, y, z);
  return node != nullptr && tree.isNodeOccupied(node);
}

TEST(OctreeMap, WallIsOccupiedAndSpaceInFrontIsFree) {
  OctreeConfig config;
  config.resolution_m = 0.05;
  OctreeMap map(config, test_camera());
  map.integrate(wall_scan(false, 0));
  const auto& tree = map.tree();
  const auto* wall = tree.search(0.0, 0.0, 3.0);
  ASSERT_NE(wall, nullptr);
  EXPECT_TRUE(tree.isNodeOccupied(wall));
  const auto* air = tree.search(0.0, 0.0, 1.5);
  ASSERT_NE(air, nullptr);
  EXPECT_FALSE(tree.isNodeOccupied(air));
  // Colour averaged from the scan (BGR 200,100,50 -> RGB 50,100,200).
  const auto colour = tree.search(0.0, 0.0, 3.0)->getColor();
  EXPECT_EQ(colour.r, 50);
  EXPECT_EQ(colour.b, 200);
  EXPECT_GT(map.stats().occupied_leaves, 1000u);
}

TEST(OctreeMap, RayCastingClearsAPersonWhoWalkedAway) {
  OctreeMap map(OctreeConfig{}, test_camera());
  map.integrate(wall_scan(true, 0));
  ASSERT_TRUE(map.tree().isNodeOccupied(map.tree().search(0.0, 0.0, 1.5)));
  for (int i = 1; i <= 3; ++i) map.integrate(wall_scan(false, static_cast<std::uint64_t>(i)));
  EXPECT_FALSE(map.tree().isNodeOccupied(map.tree().search(0.0, 0.0, 1.5)));
  EXPECT_TRUE(map.tree().isNodeOccupied(map.tree().search(0.0, 0.0, 3.0)));
}

TEST(OctreeMap, ExcludedPixelsAreNotInserted) {
  OctreeMap map(OctreeConfig{}, test_camera());
  KeyframeScan scan = wall_scan(true, 0);
  scan.exclude_mask = scan.depth_m < 2.0f;
  map.integrate(scan);
  const auto* node = map.tree().search(0.0, 0.0, 1.5);
  EXPECT_TRUE(node == nullptr || !map.tree().isNodeOccupied(node));
}

TEST(OctreeMap, FilesOpenWithTheOctomapLibrary) {
  OctreeMap map(OctreeConfig{}, test_camera());
  map.integrate(wall_scan(false, 0));
  const fs::path dir = fs::temp_directory_path() / "ddl_octomap_test";
  fs::create_directories(dir);
  map.write_ot((dir / "map.ot").string());
  map.write_bt((dir / "map.bt").string());
  map.write_ply((dir / "map.ply").string());

  std::unique_ptr<::octomap::AbstractOcTree> read(
      ::octomap::AbstractOcTree::read((dir / "map.ot").string()));
  ASSERT_NE(read, nullptr);
  auto* colour_tree = dynamic_cast<::octomap::ColorOcTree*>(read.get());
  ASSERT_NE(colour_tree, nullptr);
  EXPECT_EQ(colour_tree->getResolution(), 0.05);
  EXPECT_TRUE(colour_tree->isNodeOccupied(colour_tree->search(0.1, -0.1, 3.0)));

  ::octomap::OcTree occupancy(0.1);
  ASSERT_TRUE(occupancy.readBinary((dir / "map.bt").string()));
  EXPECT_EQ(occupancy.getResolution(), 0.05);
  EXPECT_TRUE(occupied(occupancy, 0.1, -0.1, 3.0));
  EXPECT_FALSE(occupied(occupancy, 0.0, 0.0, 1.0));
  EXPECT_GT(fs::file_size(dir / "map.ply"), 1000u);
  const cv::Mat top = map.render(false, 1);
  EXPECT_GT(cv::countNonZero(top.reshape(1) != 255), 1000);
  fs::remove_all(dir);
}

TEST(OctreeMap, ConfigErrorsNameTheKey) {
  OctreeConfig config;
  config.resolution_m = 0;
  try {
    config.validate();
    FAIL();
  } catch (const ConfigError& e) {
    EXPECT_NE(std::string(e.what()).find("octomap.resolution_m"), std::string::npos);
  }
}

}  // namespace
}  // namespace ddl::octomap
