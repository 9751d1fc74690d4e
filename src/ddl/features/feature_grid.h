#pragma once
// A uniform grid over the image that answers "which keypoints lie within r pixels of (u, v), on
// pyramid levels [min_level, max_level]?" in time proportional to the cells touched (ORB-SLAM2's
// Frame grid and GetFeaturesInArea, used by projection matching in tracking).
// Immutable after construction: const methods may be called from any thread.

#include <cstddef>
#include <cstdint>
#include <limits>
#include <opencv2/core.hpp>
#include <vector>

namespace ddl::features {

/// Shape of the search window of FeatureGrid::features_in_area().
enum class SearchWindow {
  kSquare,  // |x - u| < r and |y - v| < r (ORB-SLAM2's GetFeaturesInArea)
  kCircle,  // (x - u)^2 + (y - v)^2 < r^2
};

class FeatureGrid {
 public:
  /// No level limit for features_in_area().
  static constexpr int kAnyLevel = std::numeric_limits<int>::max();
  /// ORB-SLAM2's grid resolution for 640x480 images (10 x 10 pixel cells).
  static constexpr int kDefaultCols = 64;
  static constexpr int kDefaultRows = 48;

  FeatureGrid() = default;
  /// Buckets `keypoints` (pt in pixels, octave = pyramid level) into cols x rows cells covering
  /// `bounds` (usually the image rectangle, or the undistorted image bounds). Keypoints outside
  /// `bounds` are stored in the nearest border cell, so every search stays exact.
  /// Throws ddl::ConfigError ("grid.cols"/"grid.rows"/"grid.bounds") on invalid arguments.
  FeatureGrid(const std::vector<cv::KeyPoint>& keypoints, const cv::Rect2f& bounds,
              int cols = kDefaultCols, int rows = kDefaultRows);

  /// Indices (into the constructor's `keypoints`) of the keypoints inside the window of
  /// half-size / radius `r` around (u, v) whose octave is in [min_level, max_level]. Exactly the
  /// brute-force answer. Order: by cell (row-major), ascending index within a cell.
  std::vector<std::size_t> features_in_area(float u, float v, float r, int min_level = 0,
                                            int max_level = kAnyLevel,
                                            SearchWindow window = SearchWindow::kSquare) const;
  /// The same, writing into `out` (cleared first) to reuse its storage in loops.
  void features_in_area(float u, float v, float r, int min_level, int max_level,
                        SearchWindow window, std::vector<std::size_t>& out) const;

  std::size_t size() const { return entries_.size(); }
  int cols() const { return cols_; }
  int rows() const { return rows_; }
  const cv::Rect2f& bounds() const { return bounds_; }
  /// Cell (column, row) holding a point, clamped to the grid.
  cv::Point cell_of(float x, float y) const;

 private:
  struct Entry {
    float x, y;
    std::int32_t octave;
    std::uint32_t index;
  };

  cv::Rect2f bounds_;
  int cols_ = 0;
  int rows_ = 0;
  float inv_cell_w_ = 0.0f;
  float inv_cell_h_ = 0.0f;
  std::vector<std::uint32_t> cell_start_;  // cols*rows + 1 offsets into entries_
  std::vector<Entry> entries_;             // grouped by cell, row-major
};

}  // namespace ddl::features
