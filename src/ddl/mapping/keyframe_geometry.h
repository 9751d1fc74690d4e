#pragma once
// Small geometric helpers on keyframes shared by local mapping and loop closing: the RGB-D
// camera model (pinhole + virtual baseline, ORB-SLAM2's convention u_right = u - bf / z), feature
// measurements for the optimisers, back-projection of features with depth and the in-image test.
// Pure functions; thread-safe.

#include <cstddef>
#include <optional>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"
#include "ddl/map/keyframe.h"
#include "ddl/optimization/types.h"

namespace ddl::mapping {

using optimization::CameraIntrinsics;

/// Intrinsics of the (undistorted) camera with the virtual baseline bf [m px].
CameraIntrinsics make_intrinsics(const camera::PinholeCamera& camera, double bf);

/// Pixel of a camera-frame point (z must be > 0).
inline Vec2d project(const CameraIntrinsics& camera, const Vec3d& p_c) {
  return {camera.fx * p_c.x() / p_c.z() + camera.cx, camera.fy * p_c.y() / p_c.z() + camera.cy};
}

/// FrameFeatures::is_stereo: feature i has a depth measurement with a non-negative virtual right
/// coordinate (ORB-SLAM2's rule).
inline bool has_stereo(const map::FrameFeatures& features, std::size_t i) {
  return features.is_stereo(i);
}

/// The measurement of feature i for the optimisers: (u, v) and, with depth, u_right; information
/// of its pyramid level.
optimization::Measurement measurement_of(const map::FrameFeatures& features, std::size_t i);

/// World point of feature i back-projected with its depth at pose T_c_w; nullopt without depth.
std::optional<Vec3d> unproject_feature_w(const map::FrameFeatures& features, std::size_t i,
                                         const CameraIntrinsics& camera, const SE3& T_c_w);

/// Whether a pixel lies inside the region the keyframe's features come from (the grid bounds:
/// the undistorted image bounds).
bool in_image(const map::FrameFeatures& features, const Vec2d& uv);

/// Squared reprojection error of a camera-frame point against feature i, divided by the level's
/// sigma^2 (chi2 with 2 dof, or 3 dof including u_right when the feature has depth).
double reprojection_chi2(const map::FrameFeatures& features, std::size_t i,
                         const CameraIntrinsics& camera, const Vec3d& p_c);

}  // namespace ddl::mapping
