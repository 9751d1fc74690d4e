#include "ddl/features/feature_grid.h"

#include <fmt/format.h>

#include <algorithm>
#include <cmath>

#include "ddl/core/error.h"

namespace ddl::features {

FeatureGrid::FeatureGrid(const std::vector<cv::KeyPoint>& keypoints, const cv::Rect2f& bounds,
                         int cols, int rows)
    : bounds_(bounds), cols_(cols), rows_(rows) {
  if (cols < 1 || cols > 4096) {
    throw ConfigError::for_key("grid.cols", fmt::format("must be in 1..4096 (got {})", cols));
  }
  if (rows < 1 || rows > 4096) {
    throw ConfigError::for_key("grid.rows", fmt::format("must be in 1..4096 (got {})", rows));
  }
  if (!(bounds.width > 0.0f && bounds.height > 0.0f && std::isfinite(bounds.x) &&
        std::isfinite(bounds.y) && std::isfinite(bounds.width) && std::isfinite(bounds.height))) {
    throw ConfigError::for_key("grid.bounds",
                               fmt::format("must be a finite rectangle of positive size (got "
                                           "x {} y {} width {} height {})",
                                           bounds.x, bounds.y, bounds.width, bounds.height));
  }
  inv_cell_w_ = static_cast<float>(cols) / bounds.width;
  inv_cell_h_ = static_cast<float>(rows) / bounds.height;

  // Counting sort by cell: entries of one cell are contiguous and in index order.
  const std::size_t num_cells = static_cast<std::size_t>(cols) * rows;
  cell_start_.assign(num_cells + 1, 0);
  std::vector<std::uint32_t> cell_index(keypoints.size());
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const cv::Point c = cell_of(keypoints[i].pt.x, keypoints[i].pt.y);
    cell_index[i] = static_cast<std::uint32_t>(c.y * cols + c.x);
    ++cell_start_[cell_index[i] + 1];
  }
  for (std::size_t c = 0; c < num_cells; ++c) cell_start_[c + 1] += cell_start_[c];
  entries_.resize(keypoints.size());
  std::vector<std::uint32_t> fill(cell_start_.begin(), cell_start_.end() - 1);
  for (std::size_t i = 0; i < keypoints.size(); ++i) {
    const cv::KeyPoint& kp = keypoints[i];
    entries_[fill[cell_index[i]]++] = {kp.pt.x, kp.pt.y, kp.octave, static_cast<std::uint32_t>(i)};
  }
}

cv::Point FeatureGrid::cell_of(float x, float y) const {
  // floor of a monotonic expression, then clamped (also for values far outside). A NaN goes to
  // cell 0: `!(f >= 0)` holds for it, where a cast to int would be undefined (review, stop 26).
  const float fx = std::floor((x - bounds_.x) * inv_cell_w_);
  const float fy = std::floor((y - bounds_.y) * inv_cell_h_);
  const int cx =
      !(fx >= 0.0f) ? 0 : (fx >= static_cast<float>(cols_ - 1) ? cols_ - 1 : static_cast<int>(fx));
  const int cy =
      !(fy >= 0.0f) ? 0 : (fy >= static_cast<float>(rows_ - 1) ? rows_ - 1 : static_cast<int>(fy));
  return {cx, cy};
}

std::vector<std::size_t> FeatureGrid::features_in_area(float u, float v, float r, int min_level,
                                                       int max_level, SearchWindow window) const {
  std::vector<std::size_t> out;
  features_in_area(u, v, r, min_level, max_level, window, out);
  return out;
}

void FeatureGrid::features_in_area(float u, float v, float r, int min_level, int max_level,
                                   SearchWindow window, std::vector<std::size_t>& out) const {
  out.clear();
  if (entries_.empty() || !(r > 0.0f) || !std::isfinite(u) || !std::isfinite(v)) return;
  // The cell range is padded by a hair so that float rounding of u - r can never leave out a
  // cell holding a point that passes the exact test below.
  const float pad = r * 1e-5f + 1e-3f;
  const cv::Point lo = cell_of(u - r - pad, v - r - pad);
  const cv::Point hi = cell_of(u + r + pad, v + r + pad);
  const float r2 = r * r;
  for (int cy = lo.y; cy <= hi.y; ++cy) {
    for (int cx = lo.x; cx <= hi.x; ++cx) {
      const std::size_t cell = static_cast<std::size_t>(cy) * cols_ + cx;
      for (std::uint32_t k = cell_start_[cell]; k < cell_start_[cell + 1]; ++k) {
        const Entry& e = entries_[k];
        if (e.octave < min_level || e.octave > max_level) continue;
        const float dx = e.x - u;
        const float dy = e.y - v;
        const bool inside = window == SearchWindow::kSquare
                                ? (std::fabs(dx) < r && std::fabs(dy) < r)
                                : (dx * dx + dy * dy < r2);
        if (inside) out.push_back(e.index);
      }
    }
  }
}

}  // namespace ddl::features
