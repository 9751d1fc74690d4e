#pragma once
// The OctoMap map (DDL-SLAM section III-E): repaired keyframes (colour + depth at their optimized
// pose) are integrated into an octomap::ColorOcTree by ray casting, so free space along each ray
// clears what moving objects left in earlier frames. Pixels still marked dynamic (unfilled by
// inpainting) are not inserted as endpoints.
// OctreeMap is not thread-safe by itself; pipeline::DenseMapper owns one and uses it from its
// own thread.

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <string>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"

namespace octomap {
class ColorOcTree;
}

namespace ddl::octomap {

struct OctreeConfig {
  double resolution_m = 0.05;  // voxel edge; 5 cm resolves desks and chairs at room scale
  double max_range_m = 4.0;    // rays longer than this (camera centre to point, not depth z) are
                               // truncated: they clear free space up to it, mark nothing occupied
                               // (Kinect noise grows ~ z^2)
  double min_range_m = 0.3;    // closer measurements are ignored
  int pixel_stride = 4;        // use every n-th pixel in u and v (speed; voxels are larger anyway)
  double prob_hit = 0.7;       // OctoMap sensor model
  double prob_miss = 0.4;
  double clamping_min = 0.12;
  double clamping_max = 0.97;
  double occupancy_threshold = 0.5;

  /// Throws ddl::ConfigError naming "dense.octree.<field>" (its place in the settings).
  void validate() const;
};

/// One keyframe's contribution.
struct KeyframeScan {
  std::uint64_t keyframe_id = 0;
  SE3 T_w_c;
  cv::Mat bgr;           // CV_8UC3 (repaired)
  cv::Mat depth_m;       // CV_32FC1 metres (repaired), 0 = none
  cv::Mat exclude_mask;  // CV_8UC1 non-zero = do not insert (still dynamic); may be empty
  /// 1: the images are the camera's. OctreeConfig::pixel_stride: they hold only the pixels
  /// integrate() uses, pixel (u, v) standing for the camera's (u * step, v * step)
  /// (subsampled(): the same voxels at a sixteenth of the memory for the default stride 4).
  int pixel_step = 1;
};

/// The pixels of `scan` that OctreeMap::integrate uses with `pixel_stride`, and only those
/// (pixel_step = pixel_stride): integrating it gives the same octree as integrating `scan`.
KeyframeScan subsampled(const KeyframeScan& scan, int pixel_stride);

struct OctreeStats {
  std::size_t scans_integrated = 0;
  std::size_t occupied_leaves = 0;
  std::size_t free_leaves = 0;
  double last_integration_ms = 0.0;
};

class OctreeMap {
 public:
  OctreeMap(const OctreeConfig& config, const camera::PinholeCamera& camera);
  ~OctreeMap();
  OctreeMap(const OctreeMap&) = delete;
  OctreeMap& operator=(const OctreeMap&) = delete;

  /// Throws ddl::Error when scan.pixel_step is neither 1 nor the configured pixel_stride.
  void integrate(const KeyframeScan& scan);
  /// Drops everything (before re-integration with corrected poses).
  void clear();

  /// Writes the colour octree (.ot, ColorOcTree) and the occupancy tree (.bt, binary OcTree),
  /// readable by OctoMap's tools (octovis, binvox2bt's counterparts). Throws ddl::Error naming
  /// the file on failure.
  void write_ot(const std::string& path) const;
  void write_bt(const std::string& path) const;
  /// ASCII PLY of occupied voxel centres with colour.
  void write_ply(const std::string& path) const;
  /// PNG rendering of the occupied voxels: top view (looking down, against the world direction
  /// `up_w`, which points at the viewer) or oblique (tilted from there). Throws ddl::Error for a
  /// zero `up_w`.
  cv::Mat render(bool oblique, const Vec3d& up_w, int width = 800, int height = 600) const;

  OctreeStats stats() const;
  const ::octomap::ColorOcTree& tree() const { return *tree_; }
  const OctreeConfig& config() const { return config_; }

 private:
  OctreeConfig config_;
  camera::PinholeCamera camera_;
  std::unique_ptr<::octomap::ColorOcTree> tree_;
  std::size_t scans_ = 0;
  double last_ms_ = 0.0;
};

/// The occupied voxels of a map file, as evaluations need them.
struct OccupiedVoxels {
  double resolution_m = 0.0;
  std::vector<Vec3d> centres;  // map frame; one per finest-level voxel
};

/// Reads a map written by OctreeMap (.ot: any OcTree type through AbstractOcTree::read; .bt:
/// binary OcTree) with the OctoMap library and lists the centres of its occupied voxels. A pruned
/// leaf (a coarser node standing for 8^k equal children) is expanded into its finest-level voxels,
/// so every occupied voxel counts once whatever the tree's pruning. Throws ddl::InputError naming
/// the file when it cannot be read.
OccupiedVoxels read_occupied_voxels(const std::string& path);

}  // namespace ddl::octomap
