#pragma once
// Metrics of the dense stage (background inpainting and the OctoMap map) against the synthetic
// generator's exact ground truth (docs/dense.md): pixel errors of repaired keyframes against the
// rendered background, the background pixels earlier keyframes could have supplied, and the
// classification of occupied voxels by their distance to the true static and dynamic geometry.
// Images: colour CV_8UC3, depth CV_32FC1 metres (0 = none), masks CV_8UC1 (non-zero = set).
// Thread-safety: pure functions and plain values; PointGrid is safe for concurrent const use.

#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>
#include <unordered_map>
#include <unordered_set>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"
#include "ddl/core/types.h"

namespace ddl::eval {

/// Squared colour differences summed over pixels and channels; pools over frames.
struct ColourError {
  double sum_squared = 0.0;
  std::uint64_t pixels = 0;

  /// 10 log10(255^2 / MSE), MSE over the 3 channels of every pixel; +inf for MSE 0, NaN without
  /// pixels.
  double psnr_db() const;
  ColourError& operator+=(const ColourError& other);
};

/// |a - b| of the pixels of `mask` where both depths are > 0; pools over frames.
struct DepthError {
  std::vector<float> abs_m;
  std::uint64_t missing = 0;  // mask pixels where either depth is 0 (not in abs_m)

  /// Median of abs_m (numpy.median); NaN when empty.
  double median_m() const;
  DepthError& operator+=(const DepthError& other);
};

/// Throws std::invalid_argument on type or size mismatch.
ColourError colour_error(const cv::Mat& bgr, const cv::Mat& reference_bgr, const cv::Mat& mask);
DepthError depth_error(const cv::Mat& depth_m, const cv::Mat& reference_depth_m,
                       const cv::Mat& mask);

/// An earlier keyframe as ground truth knows it: the true pose, the measured depth and the true
/// dynamic mask.
struct TrueView {
  SE3 T_w_c;
  cv::Mat depth_m;
  cv::Mat dynamic_mask;
};

struct SeenOptions {
  double depth_tolerance_m = 0.05;    // |measured - projected depth| below max(this, rel * z)
  double depth_tolerance_rel = 0.03;  // relative part of the tolerance
};

/// The dynamic pixels of a frame whose true background surface point (background depth
/// back-projected at the true pose T_w_c) an earlier view saw: it projects inside that view,
/// onto a pixel that is static in its true mask and whose measured depth agrees with the
/// projected depth (the point was not hidden). Pixels without background depth are never seen.
cv::Mat seen_background(const cv::Mat& dynamic_mask, const cv::Mat& background_depth_m,
                        const SE3& T_w_c, const std::vector<TrueView>& earlier,
                        const camera::PinholeCamera& camera, const SeenOptions& options = {});

/// One repaired keyframe against the truth. Pixel sets (all within the true dynamic mask D):
///   filled F = D and repair mask and not unfilled (keyframe projection or image fill);
///   seen S = seen_background(); the unfilled baseline is the original frame on the same pixels.
struct InpaintingFrameInputs {
  cv::Mat repaired_bgr, repaired_depth_m;      // the run's <stamp>_rgb/_depth.png
  cv::Mat repair_mask, unfilled;               // the run's <stamp>_mask/_unfilled.png
  cv::Mat original_bgr, original_depth_m;      // the sequence frame
  cv::Mat dynamic_mask;                        // true dynamic mask D
  cv::Mat background_bgr, background_depth_m;  // the frame without dynamic entities
  cv::Mat seen;                                // seen_background(), may be empty (none seen)
};

struct InpaintingFrameMetrics {
  double timestamp_s = 0.0;
  std::uint64_t dynamic_px = 0;      // |D|
  std::uint64_t seen_px = 0;         // |S|
  std::uint64_t filled_px = 0;       // |F|
  std::uint64_t filled_seen_px = 0;  // |F and S|
  std::uint64_t repair_mask_px = 0;  // pixels the run repaired (any, also outside D)
  ColourError filled_rgb;            // repaired vs background over F
  ColourError filled_rgb_original;   // original vs background over F (unfilled baseline)
  ColourError dynamic_rgb;           // repaired vs background over D
  ColourError dynamic_rgb_original;  // original vs background over D
  DepthError filled_depth;           // repaired vs background depth over F
  DepthError filled_depth_original;  // original vs background depth over F

  /// Sums counts and pools errors (for a sequence total).
  InpaintingFrameMetrics& operator+=(const InpaintingFrameMetrics& other);
};

/// Throws std::invalid_argument when images are missing or differ in size or type.
InpaintingFrameMetrics evaluate_inpainted_frame(const InpaintingFrameInputs& inputs);

/// Points hashed into cubic cells for "is any point within r of q" queries (r <= cell size).
/// Points closer than `merge_m` to an already stored point's fine-grid cell are merged, so dense
/// clouds (every pixel of hundreds of frames) stay small: each stored point is the centre of a
/// fine cell, within merge_m * sqrt(3) / 2 of the points it stands for.
class PointGrid {
 public:
  PointGrid(double cell_m, double merge_m);
  void insert(const Vec3d& p);
  bool any_within(const Vec3d& q, double radius_m) const;
  std::size_t size() const { return stored_; }
  double merge_m() const { return merge_; }

 private:
  double cell_;
  double merge_;
  std::unordered_map<std::uint64_t, std::vector<Eigen::Vector3f>> cells_;
  std::unordered_set<std::uint64_t> fine_;
  std::size_t stored_ = 0;
};

struct VoxelClasses {
  std::uint64_t occupied = 0;
  std::uint64_t true_static = 0;  // within radius of the true static geometry
  std::uint64_t ghost = 0;        // not static, within radius of a true dynamic point
  std::uint64_t other = 0;        // neither (noise, drift, geometry the reference lacks)

  double fraction(std::uint64_t n) const {
    return occupied > 0 ? static_cast<double>(n) / static_cast<double>(occupied)
                        : std::numeric_limits<double>::quiet_NaN();
  }
};

enum class VoxelClass : std::uint8_t { kStatic, kGhost, kOther };

/// Classifies voxel centres (already in the ground-truth frame); `labels`, when given, receives
/// the class of each centre.
VoxelClasses classify_voxels(const std::vector<Vec3d>& centres, const PointGrid& static_points,
                             const PointGrid& dynamic_points, double radius_m,
                             std::vector<VoxelClass>* labels = nullptr);

}  // namespace ddl::eval
