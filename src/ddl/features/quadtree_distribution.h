#pragma once
// Even spatial distribution of keypoints by quadtree subdivision (ORB-SLAM2's
// "DistributeOctTree", Mur-Artal & Tardos 2017, section III-A): the region is split into nodes
// until there are as many nodes as keypoints wanted, splitting the most populated nodes first;
// each node then keeps its strongest keypoint. Keeps corners in weakly textured areas that a
// global response ranking would drop.

#include <cstdint>
#include <opencv2/core.hpp>
#include <vector>

namespace ddl::features {

/// Scratch buffers of distribute_quadtree(), reused between calls to avoid allocations.
struct QuadtreeScratch {
  struct Node {
    float x0, y0, x1, y1;  // node rectangle [x0, x1) x [y0, y1)
    int begin, end;        // range of `indices`
  };
  std::vector<int> indices;
  std::vector<Node> open;
  std::vector<Node> next_open;
  std::vector<Node> leaves;
  std::vector<std::int64_t> split_order;
};

/// Selects about `target` keypoints from `candidates` whose positions lie in `region` (points
/// outside are clamped into the border nodes). Writes the indices of the kept candidates to
/// `kept`, ascending. If there are no more candidates than `target`, all are kept. Otherwise
/// the result has between `target` and `target + 3` keypoints (a node splits into up to four),
/// except when the candidates run out of separable positions first.
/// Ties of response are broken by position (smaller y, then smaller x), so the result does not
/// depend on the order of `candidates`.
void distribute_quadtree(const std::vector<cv::KeyPoint>& candidates, const cv::Rect2f& region,
                         int target, QuadtreeScratch& scratch, std::vector<int>& kept);

}  // namespace ddl::features
