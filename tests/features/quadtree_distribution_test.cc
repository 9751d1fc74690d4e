#include "ddl/features/quadtree_distribution.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <set>

namespace ddl::features {
namespace {

std::vector<cv::KeyPoint> random_points(int n, cv::Size size, std::uint32_t seed) {
  std::mt19937 rng(seed);
  std::set<std::pair<int, int>> used;
  std::vector<cv::KeyPoint> points;
  while (static_cast<int>(points.size()) < n) {
    const int x = static_cast<int>(rng() % size.width);
    const int y = static_cast<int>(rng() % size.height);
    if (!used.insert({x, y}).second) continue;
    points.emplace_back(cv::Point2f(x, y), 7.f, -1.f, static_cast<float>(7 + rng() % 60));
  }
  return points;
}

std::set<std::pair<float, float>> positions(const std::vector<cv::KeyPoint>& kps,
                                            const std::vector<int>& kept) {
  std::set<std::pair<float, float>> out;
  for (int i : kept) out.insert({kps[i].pt.x, kps[i].pt.y});
  return out;
}

TEST(QuadtreeDistribution, KeepsEverythingWhenThereAreFewerCandidatesThanWanted) {
  const auto kps = random_points(50, {600, 400}, 1);
  QuadtreeScratch scratch;
  std::vector<int> kept;
  distribute_quadtree(kps, cv::Rect2f(0, 0, 600, 400), 80, scratch, kept);
  EXPECT_EQ(kept.size(), 50u);
  distribute_quadtree(kps, cv::Rect2f(0, 0, 600, 400), 0, scratch, kept);
  EXPECT_TRUE(kept.empty());
}

TEST(QuadtreeDistribution, KeepsTargetToTargetPlusThree) {
  const auto kps = random_points(5000, {602, 442}, 2);
  QuadtreeScratch scratch;
  std::vector<int> kept;
  for (int target : {1, 5, 60, 151, 217, 1000, 2500}) {
    distribute_quadtree(kps, cv::Rect2f(0, 0, 602, 442), target, scratch, kept);
    EXPECT_GE(static_cast<int>(kept.size()), target) << target;
    EXPECT_LE(static_cast<int>(kept.size()), target + 3) << target;
    EXPECT_TRUE(std::is_sorted(kept.begin(), kept.end()));
    EXPECT_EQ(std::adjacent_find(kept.begin(), kept.end()), kept.end()) << "duplicate index";
  }
}

TEST(QuadtreeDistribution, ResultDoesNotDependOnCandidateOrder) {
  auto kps = random_points(3000, {600, 400}, 3);
  QuadtreeScratch scratch;
  std::vector<int> kept;
  distribute_quadtree(kps, cv::Rect2f(0, 0, 600, 400), 200, scratch, kept);
  const auto expected = positions(kps, kept);
  std::mt19937 rng(4);
  std::shuffle(kps.begin(), kps.end(), rng);
  distribute_quadtree(kps, cv::Rect2f(0, 0, 600, 400), 200, scratch, kept);
  EXPECT_EQ(positions(kps, kept), expected);
}

TEST(QuadtreeDistribution, SingleNodeKeepsTheStrongestAndBreaksTiesByPosition) {
  std::vector<cv::KeyPoint> kps = {{cv::Point2f(10, 10), 7, -1, 30},
                                   {cv::Point2f(50, 20), 7, -1, 55},
                                   {cv::Point2f(40, 5), 7, -1, 55},
                                   {cv::Point2f(90, 90), 7, -1, 12}};
  QuadtreeScratch scratch;
  std::vector<int> kept;
  distribute_quadtree(kps, cv::Rect2f(0, 0, 100, 100), 1, scratch, kept);
  ASSERT_EQ(kept.size(), 1u);
  EXPECT_EQ(kept[0], 2);  // response 55, smaller y than index 1
}

TEST(QuadtreeDistribution, SparseWeakCornersSurviveNextToADenseStrongCluster) {
  // 2000 strong corners packed in one corner of the image and 40 weak ones spread elsewhere. A
  // ranking by response would keep only the cluster; the quadtree keeps every isolated corner.
  std::vector<cv::KeyPoint> kps;
  std::mt19937 rng(5);
  std::set<std::pair<int, int>> used;
  while (kps.size() < 2000) {
    const int x = static_cast<int>(rng() % 100);
    const int y = static_cast<int>(rng() % 100);
    if (used.insert({x, y}).second) kps.emplace_back(cv::Point2f(x, y), 7, -1, 80.f);
  }
  for (int i = 0; i < 40; ++i) {
    kps.emplace_back(cv::Point2f(150 + (i % 8) * 55, 130 + (i / 8) * 55), 7, -1, 8.f);
  }
  QuadtreeScratch scratch;
  std::vector<int> kept;
  distribute_quadtree(kps, cv::Rect2f(0, 0, 600, 400), 100, scratch, kept);
  const int weak_kept =
      static_cast<int>(std::count_if(kept.begin(), kept.end(), [](int i) { return i >= 2000; }));
  EXPECT_EQ(weak_kept, 40);
  EXPECT_GE(kept.size(), 100u);
}

TEST(QuadtreeDistribution, DuplicatePositionsTerminate) {
  std::vector<cv::KeyPoint> kps(500, cv::KeyPoint(cv::Point2f(20, 20), 7, -1, 10));
  kps.emplace_back(cv::Point2f(80, 80), 7, -1, 10);
  QuadtreeScratch scratch;
  std::vector<int> kept;
  distribute_quadtree(kps, cv::Rect2f(0, 0, 100, 100), 50, scratch, kept);
  EXPECT_EQ(kept.size(), 2u);  // one per distinct position
}

}  // namespace
}  // namespace ddl::features
