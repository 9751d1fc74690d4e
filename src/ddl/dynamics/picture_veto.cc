#include "ddl/dynamics/picture_veto.h"

#include <cmath>
#include <cstdint>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "ddl/core/error.h"

namespace ddl::dynamics {

void PictureVetoConfig::validate() const {
  auto fail = [](const char* key, const std::string& what) {
    throw ConfigError::for_key(std::string("dynamic.picture_veto.") + key, what);
  };
  if (reach_px < 0 || reach_px > 200) fail("reach_px", "must be in 0..200");
  if (!(continuity_m > 0)) fail("continuity_m", "must be > 0");
  if (!(continuity_quadratic >= 0)) fail("continuity_quadratic", "must be >= 0");
  if (contour_window_px < 1 || contour_window_px > 16)
    fail("contour_window_px", "must be in 1..16");
  if (!(contour_m > 0)) fail("contour_m", "must be > 0");
  if (!(contour_quadratic >= 0)) fail("contour_quadratic", "must be >= 0");
  if (hole_px < 1 || hole_px > 64) fail("hole_px", "must be in 1..64");
  if (min_near_pixels < 1) fail("min_near_pixels", "must be >= 1");
  if (max_flood_pixels < 0) fail("max_flood_pixels", "must be >= 0");
}

namespace {

/// 255 on the near side of an occluding contour: a valid pixel with, within contour_window_px,
/// a valid pixel farther by the contour threshold, or a hole in the depth image at least
/// 2 * hole_px + 1 pixels across (background beyond the sensor's range, a window, a shadow the
/// object casts). The window bridges the narrow dropouts along a contour (up to
/// contour_window_px - 1 pixels wide) that a Kinect and the generator's depth model leave.
cv::Mat near_side_contours(const cv::Mat& depth_m, const cv::Mat& source_area,
                           const PictureVetoConfig& config) {
  cv::Mat farthest;
  const int k = 2 * config.contour_window_px + 1;
  cv::dilate(depth_m, farthest, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(k, k)),
             cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  // Pixels with no valid pixel within hole_px, then everything within contour_window_px of them.
  cv::Mat beside_hole;
  cv::Mat invalid = depth_m <= 0.0f;
  if (!source_area.empty()) invalid &= source_area;  // no hole where the sensor cannot see
  const int h = 2 * config.hole_px + 1;
  cv::erode(invalid, beside_hole, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(h, h)),
            cv::Point(-1, -1), 1, cv::BORDER_CONSTANT, cv::Scalar(0));
  const int r = 2 * (config.hole_px + config.contour_window_px) + 1;
  cv::dilate(beside_hole, beside_hole, cv::getStructuringElement(cv::MORPH_RECT, cv::Size(r, r)));
  cv::Mat near(depth_m.size(), CV_8UC1, cv::Scalar(0));
  for (int v = 0; v < depth_m.rows; ++v) {
    const float* d = depth_m.ptr<float>(v);
    const float* f = farthest.ptr<float>(v);
    const std::uint8_t* b = beside_hole.ptr<std::uint8_t>(v);
    std::uint8_t* n = near.ptr<std::uint8_t>(v);
    for (int u = 0; u < depth_m.cols; ++u) {
      const double z = d[u];
      if (!(z > 0.0)) continue;
      if (b[u] != 0 || f[u] - z > config.contour_m + config.contour_quadratic * z * z) n[u] = 255;
    }
  }
  return near;
}

}  // namespace

cv::Mat drop_pictures(const cv::Mat& mask, const cv::Mat& depth_m, const PictureVetoConfig& config,
                      PictureVetoStats* stats, const cv::Mat& source_area) {
  if (stats != nullptr) *stats = {};
  if (mask.empty()) return {};
  CV_Assert(mask.type() == CV_8UC1 && depth_m.type() == CV_32FC1 && mask.size() == depth_m.size());
  CV_Assert(source_area.empty() ||
            (source_area.type() == CV_8UC1 && source_area.size() == mask.size()));
  cv::Mat out = mask.clone();
  cv::Mat labels;
  const int num_labels = cv::connectedComponents(mask != 0, labels, 8, CV_32S);
  if (stats != nullptr) stats->regions = num_labels - 1;
  if (num_labels <= 1) return out;

  // The pixels of each region (its seeds are those with depth, taken below).
  const int rows = mask.rows;
  const int cols = mask.cols;
  std::vector<std::vector<int>> pixels(static_cast<std::size_t>(num_labels));
  for (int v = 0; v < rows; ++v) {
    const int* l = labels.ptr<int>(v);
    for (int u = 0; u < cols; ++u) {
      if (l[u] > 0) pixels[static_cast<std::size_t>(l[u])].push_back(v * cols + u);
    }
  }
  // An ROI is copied: the filters below would read its parent image past its edges.
  const cv::Mat depth_image = depth_m.isSubmatrix() ? depth_m.clone() : depth_m;
  const cv::Mat near = near_side_contours(depth_image, source_area, config);
  const float* depth = depth_image.ptr<float>(0);
  const std::uint8_t* is_near = near.ptr<std::uint8_t>(0);

  // visited[i] = the region whose flood reached pixel i (regions' floods may overlap).
  std::vector<int> visited(static_cast<std::size_t>(rows) * cols, 0);
  std::vector<int> frontier;
  std::vector<int> next;
  long flooded = 0;  // pixels reached beyond the regions, over all regions (the cost bound)
  for (int label = 1; label < num_labels; ++label) {
    const std::vector<int>& region = pixels[static_cast<std::size_t>(label)];
    // Budget spent: this region and the rest are kept, unjudged.
    if (flooded >= static_cast<long>(config.max_flood_pixels)) {
      if (stats != nullptr) ++stats->unjudged;
      continue;
    }
    frontier.clear();
    int near_count = 0;
    for (const int i : region) {
      if (!(depth[i] > 0.0f)) continue;
      visited[static_cast<std::size_t>(i)] = label;
      frontier.push_back(i);
      if (is_near[i] != 0) ++near_count;
    }
    if (frontier.empty()) continue;  // no depth: nothing to judge, kept
    for (int step = 0;
         step < config.reach_px && near_count < config.min_near_pixels && !frontier.empty();
         ++step) {
      next.clear();
      for (const int i : frontier) {
        const int v = i / cols;
        const int u = i % cols;
        const double z = depth[i];
        const double tolerance = config.continuity_m + config.continuity_quadratic * z * z;
        for (int dv = -1; dv <= 1; ++dv) {
          for (int du = -1; du <= 1; ++du) {
            const int vv = v + dv;
            const int uu = u + du;
            if ((dv == 0 && du == 0) || vv < 0 || vv >= rows || uu < 0 || uu >= cols) continue;
            const int j = vv * cols + uu;
            if (visited[static_cast<std::size_t>(j)] == label || !(depth[j] > 0.0f)) continue;
            if (std::abs(depth[j] - z) >= tolerance) continue;
            visited[static_cast<std::size_t>(j)] = label;
            next.push_back(j);
            if (is_near[j] != 0) ++near_count;
          }
        }
      }
      flooded += static_cast<long>(next.size());
      frontier.swap(next);
    }
    if (near_count >= config.min_near_pixels) continue;  // stands in front of something: kept
    std::uint8_t* o = out.ptr<std::uint8_t>(0);
    for (const int i : region) o[i] = 0;
    if (stats != nullptr) {
      ++stats->dropped;
      stats->dropped_px += static_cast<long>(region.size());
    }
  }
  return out;
}

}  // namespace ddl::dynamics
