#include "ddl/octomap/octree_map.h"

#include <gtest/gtest.h>
#include <octomap/AbstractOcTree.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <set>
#include <string>
#include <tuple>

#include "config_error_check.h"
#include "ddl/core/error.h"
#include "ddl/synthetic/sequence.h"

namespace ddl::octomap {
namespace {
namespace fs = std::filesystem;

// A camera at the origin looking along world +z at a wall z = 3; optionally a person-sized box
// at z = 1.5 covering x in [-0.3, 0.3], y in [-0.8, 0.8].
KeyframeScan wall_scan(bool with_person, std::uint64_t id) {
  const auto cam = synthetic::tum3_camera();
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

template <typename Tree>
bool occupied(const Tree& tree, double x, double y, double z) {
  const auto* node = tree.search(x, y, z);
  return node != nullptr && tree.isNodeOccupied(node);
}

// max_range_m bounds the ray, as in OctoMap: a wall at z = 3.9 m with max range 4 m is mapped
// where its rays are shorter than 4 m (the image centre), not at the corners (rays up to 4.8 m);
// and a ray beyond the range still clears the space in front of it. Until 2026-11-26 depth z was
// compared: the corners' endpoints were silently dropped by OctoMap while counted as in range,
// and rays with z beyond the range were skipped, so they cleared nothing (a person who walked
// away in front of a far wall stayed in the map).
TEST(OctreeMap, MaxRangeBoundsTheRayAndLongerRaysStillClear) {
  const auto cam = synthetic::tum3_camera();
  OctreeConfig config;
  config.resolution_m = 0.05;
  config.max_range_m = 4.0;
  auto wall_at = [&](float z) {
    KeyframeScan scan;
    scan.bgr = cv::Mat(cam.height, cam.width, CV_8UC3, cv::Scalar(200, 100, 50));
    scan.depth_m = cv::Mat(cam.height, cam.width, CV_32FC1, cv::Scalar(z));
    return scan;
  };
  OctreeMap near_range(config, cam);
  near_range.integrate(wall_at(3.9f));
  OctreeConfig far_config = config;
  far_config.max_range_m = 8.0;
  OctreeMap far_range(far_config, cam);
  far_range.integrate(wall_at(3.9f));
  // The wall's occupied voxels: the rays shorter than 4 m cover the middle of the wall only.
  const auto occupied_near = near_range.stats().occupied_leaves;
  const auto occupied_far = far_range.stats().occupied_leaves;
  EXPECT_GT(occupied_near, 0u);
  EXPECT_LT(occupied_near, occupied_far);
  EXPECT_TRUE(occupied(near_range.tree(), 0.0, 0.0, 3.9));  // centre ray: 3.9 m
  // Corner ray (u, v) = (0, 0): at z = 3.9 m it is longer than 4 m.
  const Vec3d corner = cam.unproject(0, 0, 3.9);
  ASSERT_GT(corner.norm(), 4.0);
  EXPECT_FALSE(occupied(near_range.tree(), corner.x(), corner.y(), corner.z()));
  EXPECT_TRUE(occupied(far_range.tree(), corner.x(), corner.y(), corner.z()));

  // A person at 2 m in front of a wall at 4.5 m (beyond the range), then the wall alone: the
  // truncated rays clear the person's voxels.
  OctreeMap map(config, cam);
  KeyframeScan person = wall_at(4.5f);
  person.depth_m(cv::Rect(280, 200, 80, 80)).setTo(2.0f);
  map.integrate(person);
  const Vec3d person_centre = cam.unproject(320, 240, 2.0);
  ASSERT_TRUE(occupied(map.tree(), person_centre.x(), person_centre.y(), person_centre.z()));
  for (int k = 0; k < 4; ++k) map.integrate(wall_at(4.5f));
  EXPECT_FALSE(occupied(map.tree(), person_centre.x(), person_centre.y(), person_centre.z()));
}

TEST(OctreeMap, WallIsOccupiedAndSpaceInFrontIsFree) {
  OctreeConfig config;
  config.resolution_m = 0.05;
  OctreeMap map(config, synthetic::tum3_camera());
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

// A voxel's colour from one scan is the mean of its points, whatever their order: a wall striped
// by pixel columns (alternating red and blue; a 5 cm voxel at 3 m spans 9 columns, 4 or 5 of each)
// gives voxels of the mean colour (r 89 or 111, b 56 or 44). Averaging point by point, as before
// stop 15, weighted the last points most: r about 67 or 133, b about 33 or 67.
TEST(OctreeMap, AScanColoursAVoxelWithTheMeanOfItsPoints) {
  OctreeConfig config;
  config.pixel_stride = 1;
  OctreeMap map(config, synthetic::tum3_camera());
  KeyframeScan scan = wall_scan(false, 0);
  for (int u = 0; u < scan.bgr.cols; ++u) {
    scan.bgr.col(u).setTo(u % 2 == 0 ? cv::Scalar(0, 0, 200) : cv::Scalar(100, 0, 0));
  }
  map.integrate(scan);
  for (const double x : {-0.4, 0.0, 0.25}) {
    const auto* node = map.tree().search(x, 0.1, 3.0);
    ASSERT_NE(node, nullptr);
    const auto colour = node->getColor();
    EXPECT_NEAR(colour.r, 100, 15) << "x = " << x;
    EXPECT_NEAR(colour.b, 50, 10) << "x = " << x;
  }
}

TEST(OctreeMap, RayCastingClearsAPersonWhoWalkedAway) {
  OctreeMap map(OctreeConfig{}, synthetic::tum3_camera());
  map.integrate(wall_scan(true, 0));
  ASSERT_TRUE(map.tree().isNodeOccupied(map.tree().search(0.0, 0.0, 1.5)));
  for (int i = 1; i <= 3; ++i) map.integrate(wall_scan(false, static_cast<std::uint64_t>(i)));
  EXPECT_FALSE(map.tree().isNodeOccupied(map.tree().search(0.0, 0.0, 1.5)));
  EXPECT_TRUE(map.tree().isNodeOccupied(map.tree().search(0.0, 0.0, 3.0)));
}

TEST(OctreeMap, ExcludedPixelsAreNotInserted) {
  OctreeMap map(OctreeConfig{}, synthetic::tum3_camera());
  KeyframeScan scan = wall_scan(true, 0);
  scan.exclude_mask = scan.depth_m < 2.0f;
  map.integrate(scan);
  const auto* node = map.tree().search(0.0, 0.0, 1.5);
  EXPECT_TRUE(node == nullptr || !map.tree().isNodeOccupied(node));
}

std::string file_bytes(const fs::path& path) {
  std::ifstream file(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(file), std::istreambuf_iterator<char>());
}

// The dense stage keeps old keyframes only with the pixels integrate() uses (stop 20): a scan
// subsampled to them gives the same octree, voxel for voxel and colour for colour, also near the
// max range, across an exclusion mask and for an image size the stride does not divide.
TEST(OctreeMap, ASubsampledScanGivesTheSameOctree) {
  const fs::path dir = fs::temp_directory_path() / "ddl_octomap_subsampled_test";
  fs::create_directories(dir);
  for (const int stride : {1, 3, 4}) {
    OctreeConfig config;
    config.pixel_stride = stride;
    config.max_range_m = 3.2;
    OctreeMap full(config, synthetic::tum3_camera());
    OctreeMap compact(config, synthetic::tum3_camera());
    KeyframeScan scan = wall_scan(true, 0);
    scan.T_w_c = SE3(so3_exp(Vec3d(0.05, -0.1, 0.02)), Vec3d(0.1, 0.2, -0.3));
    for (int v = 0; v < scan.depth_m.rows; ++v) {  // a slanted wall around the max range
      for (int u = 0; u < scan.depth_m.cols; ++u) {
        float& z = scan.depth_m.at<float>(v, u);
        if (z > 2.0f) z = 2.6f + 0.0015f * static_cast<float>(u);
        scan.bgr.at<cv::Vec3b>(v, u)[1] = static_cast<std::uint8_t>((u * 7 + v * 13) % 256);
      }
    }
    scan.exclude_mask = cv::Mat::zeros(scan.depth_m.size(), CV_8UC1);
    cv::rectangle(scan.exclude_mask, cv::Rect(100, 50, 90, 70), cv::Scalar(255), cv::FILLED);
    full.integrate(scan);
    const KeyframeScan small = subsampled(scan, stride);
    EXPECT_EQ(small.depth_m.cols, (640 + stride - 1) / stride);
    compact.integrate(small);
    ASSERT_GT(full.stats().occupied_leaves, 1000u);
    EXPECT_EQ(compact.stats().occupied_leaves, full.stats().occupied_leaves) << stride;
    EXPECT_EQ(compact.stats().free_leaves, full.stats().free_leaves) << stride;
    full.write_ot((dir / "full.ot").string());
    compact.write_ot((dir / "compact.ot").string());
    EXPECT_EQ(file_bytes(dir / "full.ot"), file_bytes(dir / "compact.ot")) << stride;
    if (stride > 1) {
      OctreeConfig other = config;
      other.pixel_stride = stride + 1;
      OctreeMap wrong(other, synthetic::tum3_camera());
      EXPECT_THROW(wrong.integrate(small), Error);
    }
  }
  fs::remove_all(dir);
}

// A full disk and a cut-off file are clear errors naming the file. OctoMap's write(filename)
// reports success whatever happened, and its readers took a cut-off .ot for a smaller map (wrong
// voxels) or died in std::bad_alloc (found by review, 2026-11-26).
TEST(OctreeMap, FullDiskAndCutOffMapFilesAreClearErrors) {
  OctreeMap map(OctreeConfig{}, synthetic::tum3_camera());
  map.integrate(wall_scan(true, 0));
  if (fs::exists("/dev/full")) {
    for (auto write : {&OctreeMap::write_ot, &OctreeMap::write_bt, &OctreeMap::write_ply}) {
      try {
        (map.*write)("/dev/full");
        ADD_FAILURE() << "no error writing to /dev/full";
      } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("/dev/full"), std::string::npos) << e.what();
      }
    }
  }
  const fs::path dir = fs::temp_directory_path() / "ddl_octomap_cut_test";
  fs::create_directories(dir);
  for (const std::string name : {"map.ot", "map.bt"}) {
    const fs::path whole = dir / name;
    if (name == "map.ot") {
      map.write_ot(whole.string());
    } else {
      map.write_bt(whole.string());
    }
    const auto size = fs::file_size(whole);
    EXPECT_EQ(read_occupied_voxels(whole.string()).centres.size(), map.stats().occupied_leaves);
    for (const double share : {0.2, 0.5, 0.7, 0.9, 0.99}) {
      const fs::path cut = dir / ("cut_" + name);
      fs::copy_file(whole, cut, fs::copy_options::overwrite_existing);
      fs::resize_file(cut, static_cast<std::uintmax_t>(share * static_cast<double>(size)));
      try {
        const auto voxels = read_occupied_voxels(cut.string());
        ADD_FAILURE() << name << " cut to " << share << " read as " << voxels.centres.size()
                      << " voxels";
      } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(cut.string()), std::string::npos) << e.what();
      }
    }
  }
  fs::remove_all(dir);
}

TEST(OctreeMap, FilesOpenWithTheOctomapLibrary) {
  OctreeMap map(OctreeConfig{}, synthetic::tum3_camera());
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
  // Every voxel of the wall, read back: all occupied voxels lie on the plane z = 3 (the voxel
  // layer [3.00, 3.05) or, from depth rounding, the one below), inside the camera's view of it
  // (3 m * 320 / 535 = 1.8 m left and right, 3 m * 248 / 539 = 1.4 m up and down), and they
  // cover its 3.6 m x 2.7 m (the camera sees all of it; pixel_stride 4 = 2.2 cm at 3 m < 5 cm).
  for (const std::string file : {"map.ot", "map.bt"}) {
    const OccupiedVoxels voxels = read_occupied_voxels((dir / file).string());
    EXPECT_EQ(voxels.resolution_m, 0.05);
    EXPECT_EQ(voxels.centres.size(), map.stats().occupied_leaves) << file;
    std::set<std::pair<long, long>> cells;
    for (const Vec3d& c : voxels.centres) {
      EXPECT_NEAR(c.z(), 3.0, 0.05) << file;
      EXPECT_LT(std::abs(c.x()), 1.85) << file;
      EXPECT_LT(std::abs(c.y()), 1.45) << file;
      cells.insert({std::lround(std::floor(c.x() / 0.05)), std::lround(std::floor(c.y() / 0.05))});
    }
    const double wall_cells = (2 * 3.0 * 320.1 / 535.4) * (2 * 3.0 * 247.6 / 539.2) / 0.0025;
    EXPECT_GT(static_cast<double>(cells.size()), 0.95 * wall_cells) << file;
  }
  const cv::Mat top = map.render(false, Vec3d(0.0, -1.0, 0.0));
  EXPECT_GT(cv::countNonZero(top.reshape(1) != 255), 1000);
  fs::remove_all(dir);
}

// The top view shows what is on top: a green table above a red floor (the SLAM world's y points
// down, so up is -y), where the world's x and z put it (x right, z up the image), not mirrored.
// Until stop 32 the up axis had no sign and +y was taken as up: the view was from below, and the
// floor hid the table (found by review).
TEST(OctreeMap, TheTopViewShowsWhatIsAboveFromAbove) {
  const auto cam = synthetic::tum3_camera();
  OctreeConfig config;
  config.pixel_stride = 1;
  OctreeMap map(config, cam);
  // A camera 2 m above the floor (y = +1.5 is the floor, y = +0.8 the table top), looking down:
  // its z axis is the world's +y, its x axis the world's x.
  const SE3 T_w_c(Quatd(Eigen::AngleAxisd(-M_PI / 2.0, Vec3d::UnitX())), Vec3d(0.0, -0.5, 0.0));
  ASSERT_NEAR((T_w_c * Vec3d(0.0, 0.0, 1.3)).y(), 0.8, 1e-9);  // the premise: 1.3 m deep is the top
  KeyframeScan floor;
  floor.T_w_c = T_w_c;
  floor.bgr = cv::Mat(cam.height, cam.width, CV_8UC3, cv::Scalar(0, 0, 255));  // red
  floor.depth_m = cv::Mat(cam.height, cam.width, CV_32FC1, cv::Scalar(2.0f));
  // First the bare floor, then the table put on it (world x in [0.2, 0.8], z in [0.2, 0.6]): the
  // floor stays under the table, so a view from below shows floor there.
  map.integrate(floor);
  KeyframeScan table = floor;
  table.bgr = floor.bgr.clone();
  table.depth_m = floor.depth_m.clone();
  for (int v = 0; v < cam.height; ++v) {
    for (int u = 0; u < cam.width; ++u) {
      const Vec3d p_w = T_w_c * cam.unproject(u, v, 1.3);
      if (p_w.x() >= 0.2 && p_w.x() <= 0.8 && p_w.z() >= 0.2 && p_w.z() <= 0.6) {
        table.depth_m.at<float>(v, u) = 1.3f;
        table.bgr.at<cv::Vec3b>(v, u) = {0, 255, 0};
      }
    }
  }
  map.integrate(table);
  const cv::Mat top = map.render(false, Vec3d(0.0, -1.0, 0.0));
  cv::Mat green, red;
  cv::inRange(top, cv::Scalar(0, 200, 0), cv::Scalar(60, 255, 60), green);
  cv::inRange(top, cv::Scalar(0, 0, 200), cv::Scalar(60, 60, 255), red);
  EXPECT_GT(cv::countNonZero(green), 5000) << "the table is hidden under the floor";
  EXPECT_GT(cv::countNonZero(red), 5000);
  // World +x is screen right, world +z screen up: the table lies in the upper right quarter.
  const cv::Moments m = cv::moments(green, true);
  ASSERT_GT(m.m00, 0.0);
  EXPECT_GT(m.m10 / m.m00, top.cols / 2.0);
  EXPECT_LT(m.m01 / m.m00, top.rows / 2.0);
  EXPECT_THROW(map.render(false, Vec3d::Zero()), Error);
}

TEST(OctreeMap, ReadingExpandsPrunedLeavesIntoVoxels) {
  // A pruned tree: 8 equal occupied children collapse into one leaf of twice the edge.
  ::octomap::OcTree tree(0.05);
  for (int i = 0; i < 2; ++i) {
    for (int j = 0; j < 2; ++j) {
      for (int k = 0; k < 2; ++k)
        tree.updateNode(0.025 + 0.05 * i, 0.025 + 0.05 * j, 0.025 + 0.05 * k, true);
    }
  }
  tree.updateNode(1.025, 0.025, 0.025, true);
  tree.prune();
  std::size_t leaves = 0;
  for (auto it = tree.begin_leafs(); it != tree.end_leafs(); ++it) ++leaves;
  ASSERT_EQ(leaves, 2u);  // the collapsed one and the single voxel
  const fs::path path = fs::temp_directory_path() / "ddl_octomap_pruned_test.bt";
  ASSERT_TRUE(tree.writeBinary(path.string()));
  const OccupiedVoxels voxels = read_occupied_voxels(path.string());
  fs::remove(path);
  ASSERT_EQ(voxels.centres.size(), 9u);
  std::set<std::tuple<long, long, long>> keys;
  for (const Vec3d& c : voxels.centres) {
    keys.insert(
        {std::lround(c.x() / 0.025), std::lround(c.y() / 0.025), std::lround(c.z() / 0.025)});
  }
  EXPECT_EQ(keys.size(), 9u);
  EXPECT_TRUE(keys.count({3, 3, 3}));   // (0.075, 0.075, 0.075)
  EXPECT_TRUE(keys.count({41, 1, 1}));  // (1.025, 0.025, 0.025)
  EXPECT_THROW(read_occupied_voxels("/nonexistent/map.ot"), InputError);
}

TEST(OctreeMap, ConfigErrorsNameTheKey) {
  OctreeConfig config;
  config.resolution_m = 0;
  EXPECT_TRUE(test_support::throws_config_error_for_key([&] { config.validate(); },
                                                        "dense.octree.resolution_m"));
}

}  // namespace
}  // namespace ddl::octomap
