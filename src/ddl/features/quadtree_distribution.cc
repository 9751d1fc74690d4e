#include "ddl/features/quadtree_distribution.h"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace ddl::features {
namespace {

using Node = QuadtreeScratch::Node;

// Nodes smaller than this in both directions are not split again. Keypoints at distinct integer
// pixels are always separated before that; the guard only ends the loop for duplicate positions.
constexpr float kMinNodeSize = 0.25f;

// Splits `node` into four quadrants by partitioning its index range in place (points on a
// dividing line go to the right / lower quadrant). Empty quadrants are dropped, single-point
// quadrants go to `leaves`, the others to `open`.
void split_node(const Node& node, const std::vector<cv::KeyPoint>& candidates,
                std::vector<int>& indices, std::vector<Node>& open, std::vector<Node>& leaves) {
  const float xm = 0.5f * (node.x0 + node.x1);
  const float ym = 0.5f * (node.y0 + node.y1);
  int* const first = indices.data() + node.begin;
  int* const last = indices.data() + node.end;
  int* const mid_y = std::partition(first, last, [&](int i) { return candidates[i].pt.y < ym; });
  int* const mid_top = std::partition(first, mid_y, [&](int i) { return candidates[i].pt.x < xm; });
  int* const mid_bottom =
      std::partition(mid_y, last, [&](int i) { return candidates[i].pt.x < xm; });
  const int base = node.begin;
  auto offset = [&](const int* p) { return base + static_cast<int>(p - first); };
  const Node children[4] = {
      {node.x0, node.y0, xm, ym, node.begin, offset(mid_top)},
      {xm, node.y0, node.x1, ym, offset(mid_top), offset(mid_y)},
      {node.x0, ym, xm, node.y1, offset(mid_y), offset(mid_bottom)},
      {xm, ym, node.x1, node.y1, offset(mid_bottom), node.end},
  };
  for (const Node& child : children) {
    const int count = child.end - child.begin;
    if (count == 0) continue;
    const bool splittable =
        count > 1 && (child.x1 - child.x0 > kMinNodeSize || child.y1 - child.y0 > kMinNodeSize);
    (splittable ? open : leaves).push_back(child);
  }
}

// Strongest keypoint of a node; equal responses are decided by position so that the choice does
// not depend on the order of the indices.
int best_in_node(const Node& node, const std::vector<cv::KeyPoint>& candidates,
                 const std::vector<int>& indices) {
  int best = indices[node.begin];
  for (int k = node.begin + 1; k < node.end; ++k) {
    const int i = indices[k];
    const cv::KeyPoint& a = candidates[i];
    const cv::KeyPoint& b = candidates[best];
    if (a.response > b.response ||
        (a.response == b.response && (a.pt.y < b.pt.y || (a.pt.y == b.pt.y && a.pt.x < b.pt.x)))) {
      best = i;
    }
  }
  return best;
}

}  // namespace

void distribute_quadtree(const std::vector<cv::KeyPoint>& candidates, const cv::Rect2f& region,
                         int target, QuadtreeScratch& scratch, std::vector<int>& kept) {
  kept.clear();
  const int n = static_cast<int>(candidates.size());
  if (n == 0 || target <= 0) return;
  if (n <= target) {
    kept.resize(n);
    std::iota(kept.begin(), kept.end(), 0);
    return;
  }

  std::vector<int>& indices = scratch.indices;
  std::vector<Node>& open = scratch.open;
  std::vector<Node>& next_open = scratch.next_open;
  std::vector<Node>& leaves = scratch.leaves;
  open.clear();
  next_open.clear();
  leaves.clear();

  // Root nodes: about square, side by side along the longer image axis (ORB-SLAM2 uses
  // round(width / height) roots; a portrait region gets one root).
  const float width = std::max(region.width, 1.0f);
  const float height = std::max(region.height, 1.0f);
  const int num_roots = std::max(1, static_cast<int>(std::lround(width / height)));
  const float root_width = width / static_cast<float>(num_roots);
  auto root_of = [&](const cv::KeyPoint& kp) {
    const int r = static_cast<int>(std::floor((kp.pt.x - region.x) / root_width));
    return std::clamp(r, 0, num_roots - 1);
  };
  // Counting sort of the candidates by root keeps `indices` in candidate order within a root.
  std::vector<int> root_start(num_roots + 1, 0);
  for (const cv::KeyPoint& kp : candidates) ++root_start[root_of(kp) + 1];
  std::partial_sum(root_start.begin(), root_start.end(), root_start.begin());
  indices.resize(n);
  {
    std::vector<int> fill(root_start.begin(), root_start.end() - 1);
    for (int i = 0; i < n; ++i) indices[fill[root_of(candidates[i])]++] = i;
  }
  for (int r = 0; r < num_roots; ++r) {
    const Node root{region.x + r * root_width, region.y,      region.x + (r + 1) * root_width,
                    region.y + height,         root_start[r], root_start[r + 1]};
    const int count = root.end - root.begin;
    if (count == 1) leaves.push_back(root);
    if (count > 1) open.push_back(root);
  }

  for (;;) {
    const std::size_t total = leaves.size() + open.size();
    if (total >= static_cast<std::size_t>(target) || open.empty()) break;
    next_open.clear();
    if (total + 3 * open.size() <= static_cast<std::size_t>(target)) {
      // Splitting every open node cannot overshoot the target: split them all.
      for (const Node& node : open) split_node(node, candidates, indices, next_open, leaves);
    } else {
      // Close to the target: split the most populated nodes first and stop as soon as the
      // target is reached. Order: point count descending, then position in `open`.
      std::vector<std::int64_t>& order = scratch.split_order;
      order.clear();
      for (std::size_t k = 0; k < open.size(); ++k) {
        const std::int64_t count = open[k].end - open[k].begin;
        order.push_back(-(count << 32) + static_cast<std::int64_t>(k));
      }
      std::sort(order.begin(), order.end());
      std::size_t done = 0;
      for (; done < order.size(); ++done) {
        const std::size_t remaining = order.size() - done;
        if (leaves.size() + next_open.size() + remaining >= static_cast<std::size_t>(target)) {
          break;
        }
        const std::size_t k = static_cast<std::size_t>(order[done] & 0xFFFFFFFF);
        split_node(open[k], candidates, indices, next_open, leaves);
      }
      // Nodes not split in this pass stay as they are.
      for (; done < order.size(); ++done) {
        next_open.push_back(open[static_cast<std::size_t>(order[done] & 0xFFFFFFFF)]);
      }
    }
    open.swap(next_open);
  }

  kept.reserve(leaves.size() + open.size());
  // A leaf normally holds one point; tiny leaves made of duplicate positions may hold more.
  for (const Node& node : leaves) kept.push_back(best_in_node(node, candidates, indices));
  for (const Node& node : open) kept.push_back(best_in_node(node, candidates, indices));
  // Candidate order (raster order of the detector) makes the output order independent of the
  // tree's internal order.
  std::sort(kept.begin(), kept.end());
}

}  // namespace ddl::features
