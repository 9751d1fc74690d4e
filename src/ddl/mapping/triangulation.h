#pragma once
// New map points from the new keyframe and its covisible keyframes (ORB-SLAM2
// LocalMapping::CreateNewMapPoints for RGB-D; ORB-SLAM T-RO 2015 section VI-D): unmatched features
// are paired by search_for_triangulation, each pair becomes a point by linear triangulation when
// the rays have more parallax than the depth measurements, else by back-projecting the depth with
// the most parallax; points must lie in front of both cameras, reproject within chi2 in both and
// have distances consistent with the two keypoints' scales.
// Thread-safety: any thread; local mapping runs it on the keyframe it is processing.

#include <atomic>
#include <optional>
#include <vector>

#include "ddl/core/se3.h"
#include "ddl/map/keyframe.h"
#include "ddl/map/map.h"
#include "ddl/mapping/keyframe_geometry.h"
#include "ddl/mapping/local_mapper_config.h"

namespace ddl::mapping {

/// Linear (DLT) triangulation of normalised image coordinates xn1 = (x1, y1) seen at T1_c_w and
/// xn2 at T2_c_w (ORB-SLAM2 / Hartley-Zisserman 12.2). nullopt when the solution is at infinity.
std::optional<Vec3d> triangulate_linear(const SE3& T1_c_w, const SE3& T2_c_w, const Vec2d& xn1,
                                        const Vec2d& xn2);

struct NewPointsResult {
  std::vector<map::MapPointPtr> created;  // in creation order (neighbour by neighbour)
  bool aborted = false;                   // the abort flag cut the neighbour loop short
};

/// Creates map points between `current` and its best covisible keyframes, adding them to `map`
/// with their two observations, descriptor, normal and scale range. `abort` (may be null) is read
/// between neighbours (after the first) as ORB-SLAM2 does when a new keyframe waits.
NewPointsResult create_new_map_points(const map::KeyFramePtr& current, map::Map& map,
                                      const CameraIntrinsics& camera,
                                      const TriangulationConfig& config,
                                      const std::atomic<bool>* abort = nullptr);

}  // namespace ddl::mapping
