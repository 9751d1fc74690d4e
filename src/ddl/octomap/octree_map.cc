#include "ddl/octomap/octree_map.h"

#include <fmt/format.h>
#include <octomap/AbstractOcTree.h>
#include <octomap/ColorOcTree.h>
#include <octomap/OcTree.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <unordered_map>

#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"
#include "ddl/core/timing.h"

namespace ddl::octomap {

void OctreeConfig::validate() const {
  auto fail = [](const char* key, const char* what) {
    throw ConfigError::for_key(std::string("dense.octree.") + key, what);
  };
  if (!(resolution_m >= 0.005 && resolution_m <= 1.0))
    fail("resolution_m", "must be in [0.005, 1]");
  if (!(max_range_m > min_range_m && min_range_m >= 0))
    fail("max_range_m", "must exceed min_range_m >= 0");
  if (pixel_stride < 1) fail("pixel_stride", "must be >= 1");
  if (!(prob_hit > 0.5 && prob_hit < 1.0)) fail("prob_hit", "must be in (0.5, 1)");
  if (!(prob_miss > 0.0 && prob_miss < 0.5)) fail("prob_miss", "must be in (0, 0.5)");
  if (!(clamping_min > 0 && clamping_min < clamping_max && clamping_max < 1)) {
    fail("clamping_min", "need 0 < clamping_min < clamping_max < 1");
  }
  if (!(occupancy_threshold > 0 && occupancy_threshold < 1))
    fail("occupancy_threshold", "must be in (0, 1)");
}

OctreeMap::OctreeMap(const OctreeConfig& config, const camera::PinholeCamera& camera)
    : config_(config), camera_(camera) {
  config_.validate();
  clear();
}

OctreeMap::~OctreeMap() = default;

void OctreeMap::clear() {
  tree_ = std::make_unique<::octomap::ColorOcTree>(config_.resolution_m);
  tree_->setProbHit(config_.prob_hit);
  tree_->setProbMiss(config_.prob_miss);
  tree_->setClampingThresMin(config_.clamping_min);
  tree_->setClampingThresMax(config_.clamping_max);
  tree_->setOccupancyThres(config_.occupancy_threshold);
  scans_ = 0;
}

KeyframeScan subsampled(const KeyframeScan& scan, int pixel_stride) {
  if (pixel_stride < 1 || scan.pixel_step != 1) {
    throw Error("octree: subsampled() takes a full-resolution scan and a stride >= 1");
  }
  const auto pick = [pixel_stride](const cv::Mat& image) {
    if (image.empty()) return cv::Mat();
    const int rows = (image.rows + pixel_stride - 1) / pixel_stride;
    const int cols = (image.cols + pixel_stride - 1) / pixel_stride;
    cv::Mat out(rows, cols, image.type());
    const std::size_t bytes = image.elemSize();
    for (int v = 0; v < rows; ++v) {
      const std::uint8_t* in_row = image.ptr(v * pixel_stride);
      std::uint8_t* out_row = out.ptr(v);
      for (int u = 0; u < cols; ++u) {
        std::memcpy(out_row + u * bytes, in_row + u * pixel_stride * bytes, bytes);
      }
    }
    return out;
  };
  KeyframeScan out{scan.keyframe_id,        scan.T_w_c,  pick(scan.bgr), pick(scan.depth_m),
                   pick(scan.exclude_mask), pixel_stride};
  return out;
}

void OctreeMap::integrate(const KeyframeScan& scan) {
  Stopwatch watch;
  ::octomap::Pointcloud cloud;
  const Mat3d R = scan.T_w_c.rotation();
  const Vec3d t = scan.T_w_c.translation();
  if (scan.pixel_step != 1 && scan.pixel_step != config_.pixel_stride) {
    throw Error(fmt::format("octree: a scan subsampled by {} does not fit pixel_stride {}",
                            scan.pixel_step, config_.pixel_stride));
  }
  const int scale = scan.pixel_step;  // image pixel -> camera pixel
  const int stride = scale == 1 ? config_.pixel_stride : 1;
  // The scan's colour of a voxel is the mean of its points (one tree search per voxel, not per
  // point); it is averaged into the voxel's colour so far, after the insertion. Colours go to the
  // leaves (found by key, which needs no inner node); one update of the inner nodes afterwards
  // sets their occupancy and colour.
  struct ColourSum {
    ::octomap::OcTreeKey key;
    std::uint32_t b = 0, g = 0, r = 0, n = 0;
  };
  std::vector<ColourSum> sums;  // in the order the voxels are first seen
  std::unordered_map<::octomap::OcTreeKey, std::size_t, ::octomap::OcTreeKey::KeyHash> voxel;
  const ::octomap::point3d origin(static_cast<float>(t.x()), static_cast<float>(t.y()),
                                  static_cast<float>(t.z()));
  for (int v = 0; v < scan.depth_m.rows; v += stride) {
    const float* drow = scan.depth_m.ptr<float>(v);
    const std::uint8_t* xrow = scan.exclude_mask.empty() ? nullptr : scan.exclude_mask.ptr(v);
    for (int u = 0; u < scan.depth_m.cols; u += stride) {
      const float z = drow[u];
      if (!(z >= config_.min_range_m)) continue;  // also no measurement (0) and NaN
      if (xrow != nullptr && xrow[u] != 0) continue;
      const Vec3d p_c = camera_.unproject(u * scale, v * scale, z);
      const Vec3d p_w = R * p_c + t;
      const ::octomap::point3d p(static_cast<float>(p_w.x()), static_cast<float>(p_w.y()),
                                 static_cast<float>(p_w.z()));
      cloud.push_back(p);
      ::octomap::OcTreeKey key;  // the voxel of the point as inserted (floats)
      if (!tree_->coordToKeyChecked(p, key)) continue;
      const auto [it, added] = voxel.try_emplace(key, sums.size());
      if (added) sums.push_back({key});
      ColourSum& sum = sums[it->second];
      const cv::Vec3b& bgr = scan.bgr.at<cv::Vec3b>(v, u);
      sum.b += bgr[0];
      sum.g += bgr[1];
      sum.r += bgr[2];
      ++sum.n;
    }
  }
  tree_->insertPointCloud(cloud, origin, config_.max_range_m, /*lazy_eval=*/true,
                          /*discretize=*/true);
  auto mean = [](std::uint32_t total, std::uint32_t n) {
    return static_cast<std::uint8_t>((total + n / 2) / n);
  };
  for (const ColourSum& sum : sums) {
    // max_range_m bounds the ray (OctoMap's meaning): a longer ray still clears the space along
    // its first max_range_m but marks nothing occupied, so its voxel is not coloured. With
    // discretize, OctoMap decides that for the voxel's centre, not for the points in it: the same
    // test here, in its float arithmetic, so that no voxel is occupied without a colour or coloured
    // while free (until 2026-11-27 each point's own range decided, about 4 cm either side of it).
    if (!((tree_->keyToCoord(sum.key) - origin).norm() <= config_.max_range_m)) continue;
    tree_->averageNodeColor(sum.key, mean(sum.r, sum.n), mean(sum.g, sum.n), mean(sum.b, sum.n));
  }
  tree_->updateInnerOccupancy();
  ++scans_;
  last_ms_ = watch.elapsed_ms();
}

// OctoMap's write(filename) reports success whatever the stream did (a full disk included), so
// the files are written through our own stream, checked after it is closed, and renamed into
// place (core/filesystem.h): an interrupted write leaves no half-written octree, which OctoMap
// would read without complaint.
void OctreeMap::write_ot(const std::string& path) const {
  write_file_atomically(
      path, "colour octree", [&](std::ostream& out) { return tree_->write(out); }, true);
}

void OctreeMap::write_bt(const std::string& path) const {
  ::octomap::OcTree occupancy(config_.resolution_m);
  occupancy.setProbHit(config_.prob_hit);
  occupancy.setProbMiss(config_.prob_miss);
  occupancy.setClampingThresMin(config_.clamping_min);
  occupancy.setClampingThresMax(config_.clamping_max);
  occupancy.setOccupancyThres(config_.occupancy_threshold);
  for (auto it = tree_->begin_leafs(), end = tree_->end_leafs(); it != end; ++it) {
    ::octomap::OcTreeNode* node = occupancy.setNodeValue(it.getKey(), it->getLogOdds(), true);
    (void)node;
  }
  occupancy.updateInnerOccupancy();
  write_file_atomically(
      path, "occupancy octree", [&](std::ostream& out) { return occupancy.writeBinary(out); },
      true);
}

void OctreeMap::write_ply(const std::string& path) const {
  std::vector<std::pair<::octomap::point3d, ::octomap::ColorOcTreeNode::Color>> voxels;
  for (auto it = tree_->begin_leafs(), end = tree_->end_leafs(); it != end; ++it) {
    if (tree_->isNodeOccupied(*it)) voxels.emplace_back(it.getCoordinate(), it->getColor());
  }
  write_file_atomically(path, "the voxel point cloud", [&](std::ostream& file) {
    file << "ply\nformat ascii 1.0\ncomment DDL-SLAM occupied voxel centres\n"
         << "element vertex " << voxels.size() << "\n"
         << "property float x\nproperty float y\nproperty float z\n"
         << "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n";
    for (const auto& [p, c] : voxels) {
      file << p.x() << ' ' << p.y() << ' ' << p.z() << ' ' << int(c.r) << ' ' << int(c.g) << ' '
           << int(c.b) << '\n';
    }
    return true;
  });
}

cv::Mat OctreeMap::render(bool oblique, const Vec3d& up_w, int width, int height) const {
  if (!(up_w.norm() > 1e-9) || !up_w.allFinite()) {
    throw Error("octree rendering: the up direction must be a non-zero world vector");
  }
  cv::Mat image(height, width, CV_8UC3, cv::Scalar(255, 255, 255));
  std::vector<std::pair<Vec3d, cv::Vec3b>> voxels;
  Vec3d lo = Vec3d::Constant(1e9), hi = Vec3d::Constant(-1e9);
  for (auto it = tree_->begin_leafs(), end = tree_->end_leafs(); it != end; ++it) {
    if (!tree_->isNodeOccupied(*it)) continue;
    const auto p = it.getCoordinate();
    const auto c = it->getColor();
    const Vec3d v(p.x(), p.y(), p.z());
    lo = lo.cwiseMin(v);
    hi = hi.cwiseMax(v);
    voxels.push_back({v, cv::Vec3b(c.b, c.g, c.r)});
  }
  if (voxels.empty()) return image;
  // View rotation, right-handed (a mirror image otherwise): `up_w` points out of the screen, at
  // the viewer, in the top view; screen right is the world x axis (z when up is along x) made
  // perpendicular to it, and screen up completes the frame. The oblique view tilts it by 50
  // degrees and turns it by 30 degrees. Until stop 32 the up axis had no sign: the SLAM world's
  // +y, which points down, was taken as up, so the top view showed the map from below.
  const Vec3d up = up_w.normalized();
  const Vec3d reference = std::abs(up.x()) < 0.9 ? Vec3d::UnitX() : Vec3d::UnitZ();
  const Vec3d right = (reference - reference.dot(up) * up).normalized();
  Mat3d axes;
  axes.row(0) = right.transpose();
  axes.row(1) = up.cross(right).transpose();
  axes.row(2) = up.transpose();
  Mat3d view = axes;
  if (oblique) {
    view = Mat3d(Eigen::AngleAxisd(-50.0 * M_PI / 180.0, Vec3d::UnitX()) *
                 Eigen::AngleAxisd(30.0 * M_PI / 180.0, Vec3d::UnitZ())) *
           axes;
  }
  const Vec3d centre = 0.5 * (lo + hi);
  double max_extent = 1e-6;
  std::vector<Vec3d> projected;
  projected.reserve(voxels.size());
  for (const auto& [p, c] : voxels) {
    const Vec3d q = view * (p - centre);
    projected.push_back(q);
    max_extent = std::max({max_extent, std::abs(q.x()), std::abs(q.y())});
  }
  const double scale = 0.45 * std::min(width, height) / max_extent;
  const int cell = std::max(1, static_cast<int>(std::ceil(config_.resolution_m * scale)));
  // Painter's order: far (low q.z) first, so nearer (higher) voxels are drawn on top.
  std::vector<std::size_t> order(voxels.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::sort(order.begin(), order.end(),
            [&](std::size_t l, std::size_t r) { return projected[l].z() < projected[r].z(); });
  for (std::size_t i : order) {
    const int x = static_cast<int>(width / 2 + projected[i].x() * scale);
    const int y = static_cast<int>(height / 2 - projected[i].y() * scale);
    cv::rectangle(image, cv::Rect(x - cell / 2, y - cell / 2, cell, cell),
                  cv::Scalar(voxels[i].second[0], voxels[i].second[1], voxels[i].second[2]),
                  cv::FILLED);
  }
  cv::putText(image,
              fmt::format("{} occupied voxels, {:.2f} m, {}", voxels.size(), config_.resolution_m,
                          oblique ? "oblique view" : "top view"),
              {10, height - 12}, cv::FONT_HERSHEY_SIMPLEX, 0.5, cv::Scalar(40, 40, 40), 1,
              cv::LINE_AA);
  return image;
}

OctreeStats OctreeMap::stats() const {
  OctreeStats s;
  s.scans_integrated = scans_;
  s.last_integration_ms = last_ms_;
  for (auto it = tree_->begin_leafs(), end = tree_->end_leafs(); it != end; ++it) {
    if (tree_->isNodeOccupied(*it)) {
      ++s.occupied_leaves;
    } else {
      ++s.free_leaves;
    }
  }
  return s;
}

namespace {

template <typename Tree>
void collect_occupied(const Tree& tree, OccupiedVoxels& out) {
  const double res = tree.getResolution();
  for (auto it = tree.begin_leafs(), end = tree.end_leafs(); it != end; ++it) {
    if (!tree.isNodeOccupied(*it)) continue;
    const auto c = it.getCoordinate();
    // A leaf above the finest depth covers n^3 finest voxels (n = 2^(16 - depth)).
    const int n = std::max(1, static_cast<int>(std::lround(it.getSize() / res)));
    const double first = -0.5 * it.getSize() + 0.5 * res;
    for (int i = 0; i < n; ++i) {
      for (int j = 0; j < n; ++j) {
        for (int k = 0; k < n; ++k) {
          out.centres.emplace_back(c.x() + first + i * res, c.y() + first + j * res,
                                   c.z() + first + k * res);
        }
      }
    }
  }
}

}  // namespace

OccupiedVoxels read_occupied_voxels(const std::string& path) {
  if (!std::filesystem::exists(path)) throw InputError::at(path, "no such map file");
  std::ifstream file(path, std::ios::binary);
  if (!file) throw InputError::at(path, "cannot open the map file");
  OccupiedVoxels out;
  // OctoMap reads a cut-off file without complaint (wrong voxels) or dies in bad_alloc on a
  // garbage node count: the stream state after reading and the exception tell.
  const auto truncated = [&] { return InputError::at(path, "truncated or corrupt octree data"); };
  if (std::filesystem::path(path).extension() == ".bt") {
    ::octomap::OcTree tree(0.1);
    bool ok = false;
    try {
      ok = tree.readBinary(file);
    } catch (const std::bad_alloc&) {
      throw truncated();
    }
    if (!ok) throw InputError::at(path, "not a binary OctoMap (.bt) file");
    if (file.fail()) throw truncated();
    out.resolution_m = tree.getResolution();
    collect_occupied(tree, out);
    return out;
  }
  std::unique_ptr<::octomap::AbstractOcTree> tree;
  try {
    tree.reset(::octomap::AbstractOcTree::read(file));
  } catch (const std::bad_alloc&) {
    throw truncated();
  }
  if (tree == nullptr) throw InputError::at(path, "not an OctoMap (.ot) file");
  if (file.fail()) throw truncated();
  out.resolution_m = tree->getResolution();
  if (const auto* colour = dynamic_cast<const ::octomap::ColorOcTree*>(tree.get())) {
    collect_occupied(*colour, out);
  } else if (const auto* occupancy = dynamic_cast<const ::octomap::OcTree*>(tree.get())) {
    collect_occupied(*occupancy, out);
  } else {
    throw InputError::at(path, fmt::format("unsupported octree type {}", tree->getTreeType()));
  }
  return out;
}

}  // namespace ddl::octomap
