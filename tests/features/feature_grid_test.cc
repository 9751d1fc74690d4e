#include "ddl/features/feature_grid.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <limits>
#include <random>

#include "config_error_check.h"
#include "ddl/core/error.h"

namespace ddl::features {
namespace {

std::vector<std::size_t> brute_force(const std::vector<cv::KeyPoint>& kps, float u, float v,
                                     float r, int min_level, int max_level, SearchWindow window) {
  std::vector<std::size_t> out;
  for (std::size_t i = 0; i < kps.size(); ++i) {
    const cv::KeyPoint& kp = kps[i];
    if (kp.octave < min_level || kp.octave > max_level) continue;
    const float dx = kp.pt.x - u;
    const float dy = kp.pt.y - v;
    const bool inside = window == SearchWindow::kSquare ? (std::fabs(dx) < r && std::fabs(dy) < r)
                                                        : (dx * dx + dy * dy < r * r);
    if (inside) out.push_back(i);
  }
  return out;
}

TEST(FeatureGrid, RadiusSearchEqualsBruteForce) {
  std::mt19937 rng(1);
  std::uniform_real_distribution<float> x(-20.0f, 660.0f);  // some points outside the image
  std::uniform_real_distribution<float> y(-20.0f, 500.0f);
  std::vector<cv::KeyPoint> kps;
  for (int i = 0; i < 3000; ++i) {
    kps.emplace_back(cv::Point2f(x(rng), y(rng)), 31.0f, 0.0f, 20.0f, static_cast<int>(rng() % 8));
  }
  kps.emplace_back(cv::Point2f(100.0f, 100.0f), 31.0f, 0.0f, 20.0f, 0);  // on a cell border
  const FeatureGrid grid(kps, cv::Rect2f(0, 0, 640, 480));
  EXPECT_EQ(grid.size(), kps.size());
  std::uniform_real_distribution<float> radius(0.5f, 120.0f);
  std::vector<std::size_t> found;
  for (int q = 0; q < 3000; ++q) {
    const float u = q == 0 ? 100.0f : x(rng);
    const float v = q == 0 ? 90.0f : y(rng);
    const float r = q == 0 ? 10.0f : radius(rng);
    int min_level = static_cast<int>(rng() % 8);
    int max_level = q % 3 == 0 ? FeatureGrid::kAnyLevel : min_level + static_cast<int>(rng() % 3);
    if (q % 5 == 0) min_level = 0;
    for (SearchWindow window : {SearchWindow::kSquare, SearchWindow::kCircle}) {
      grid.features_in_area(u, v, r, min_level, max_level, window, found);
      std::sort(found.begin(), found.end());
      ASSERT_EQ(found, brute_force(kps, u, v, r, min_level, max_level, window))
          << "query " << q << " at (" << u << ", " << v << ") r " << r;
    }
  }
  // The window is open: a point exactly r away in y is outside, a hair closer is inside.
  const auto border = grid.features_in_area(100.0f, 90.5f, 10.0f);
  EXPECT_NE(std::find(border.begin(), border.end(), kps.size() - 1), border.end());
  const auto outside = grid.features_in_area(100.0f, 90.0f, 10.0f);
  EXPECT_EQ(std::find(outside.begin(), outside.end(), kps.size() - 1), outside.end());
}

TEST(FeatureGrid, EmptyGridAndDegenerateQueries) {
  const FeatureGrid empty({}, cv::Rect2f(0, 0, 640, 480));
  EXPECT_TRUE(empty.features_in_area(10, 10, 50).empty());
  const FeatureGrid one({cv::KeyPoint(cv::Point2f(5, 5), 31)}, cv::Rect2f(0, 0, 640, 480));
  EXPECT_TRUE(one.features_in_area(5, 5, 0.0f).empty());
  EXPECT_EQ(one.features_in_area(5, 5, 1.0f).size(), 1u);
  EXPECT_TRUE(one.features_in_area(5, 5, 1.0f, 1).empty());  // octave 0 below min_level 1
  EXPECT_EQ(one.cell_of(-100.0f, 1e6f), cv::Point(0, FeatureGrid::kDefaultRows - 1));
  // A NaN coordinate goes to cell 0 (casting it to int is undefined; review, stop 26).
  const float nan = std::numeric_limits<float>::quiet_NaN();
  EXPECT_EQ(one.cell_of(nan, nan), cv::Point(0, 0));
  EXPECT_EQ(one.cell_of(nan, 1e6f), cv::Point(0, FeatureGrid::kDefaultRows - 1));
}

TEST(FeatureGrid, BadArgumentsNameTheKey) {
  auto rejects = [](int cols, int rows, cv::Rect2f bounds, const std::string& key) {
    return test_support::throws_config_error_for_key(
        [&] { FeatureGrid grid({}, bounds, cols, rows); }, key);
  };
  EXPECT_TRUE(rejects(0, 48, {0, 0, 640, 480}, "grid.cols"));
  EXPECT_TRUE(rejects(64, -1, {0, 0, 640, 480}, "grid.rows"));
  EXPECT_TRUE(rejects(64, 48, {0, 0, 0, 480}, "grid.bounds"));
}

}  // namespace
}  // namespace ddl::features
