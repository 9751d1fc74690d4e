#pragma once
// Relative pose of two RGB-D keyframes from matched 3D points (the scale-fixed form of ORB-SLAM2's
// Sim3Solver): RANSAC over minimal samples of three correspondences, each hypothesis the
// closed-form least-squares rigid transform (Horn, JOSA-A 1987; Umeyama, PAMI 1991, without
// scale), inliers judged by reprojection error in both images, the best model refitted on all its
// inliers. Deterministic for a given seed.
// Thread-safety: pure functions.

#include <cstdint>
#include <optional>
#include <span>
#include <vector>

#include "ddl/core/se3.h"
#include "ddl/optimization/types.h"

namespace ddl::loop {

/// Rigid transform T minimising sum |dst_i - T * src_i|^2 over >= 3 pairs; nullopt when the
/// points are degenerate (collinear or coincident).
std::optional<SE3> fit_rigid_transform(std::span<const Vec3d> src, std::span<const Vec3d> dst);

/// One matched point seen by camera 1 and camera 2.
struct PointCorrespondence {
  Vec3d p1_c = Vec3d::Zero();  ///< the point in camera-1 coordinates [m]
  Vec3d p2_c = Vec3d::Zero();  ///< its match in camera-2 coordinates [m]
  Vec2d uv1 = Vec2d::Zero();   ///< keypoint in image 1 [px]
  Vec2d uv2 = Vec2d::Zero();   ///< keypoint in image 2 [px]
  double sigma2_1 = 1.0;       ///< keypoint variance of its level in image 1 [px^2]
  double sigma2_2 = 1.0;       ///< ... in image 2
};

struct RelativePoseRansacOptions {
  int max_iterations = 300;   ///< hypotheses at most
  double probability = 0.99;  ///< stop once an all-inlier sample has been drawn this surely
  int min_inliers = 20;       ///< fewer inliers: no estimate
  double chi2 = 9.21;         ///< inlier: |reprojection error|^2 < chi2 * sigma2, in both images
  std::uint64_t seed = 1;     ///< random seed of the sampling
};

struct RelativePoseEstimate {
  SE3 T_1_2;                  ///< maps camera-2 coordinates into camera 1
  std::vector<bool> inliers;  ///< per correspondence
  int num_inliers = 0;
  int iterations = 0;  ///< hypotheses drawn
};

/// Estimates T_1_2 with p1_c ~= T_1_2 * p2_c. nullopt with fewer than min_inliers inliers.
std::optional<RelativePoseEstimate> estimate_relative_pose(
    std::span<const PointCorrespondence> correspondences,
    const optimization::CameraIntrinsics& camera, const RelativePoseRansacOptions& options);

/// Inlier test of one correspondence under T_1_2 (both reprojections, points in front).
bool is_relative_pose_inlier(const PointCorrespondence& c, const SE3& T_1_2,
                             const optimization::CameraIntrinsics& camera, double chi2);

}  // namespace ddl::loop
