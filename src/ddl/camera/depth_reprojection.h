#pragma once
// Moving a depth image to another pose of the same (undistorted) camera: the readings are
// back-projected, transformed and splatted into the other view. Used to bring a depth image
// captured a few milliseconds before or after its colour image to the colour image's instant
// (pipeline::DepthTimeAligner).
// Free function without state: callable from any thread.

#include <opencv2/core.hpp>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"

namespace ddl::camera {

/// The depth image `depth_m` (CV_32FC1, metres along the optical axis, 0 = no reading) of the
/// undistorted `camera` at pose `source`, as the same camera sees it at pose `target`:
/// `T_target_source` maps source camera coordinates into target camera coordinates. Each reading
/// goes to the target pixel nearest its projection; where several meet, the nearest surface wins
/// (a z-buffer). A pixel left without a reading whose 8 neighbours hold at least 5 (a crack
/// between the splats of one surface, not a hole of the sensor or a disocclusion) takes the
/// nearest of them. Throws std::invalid_argument for an image of another type or size.
cv::Mat reproject_depth(const cv::Mat& depth_m, const SE3& T_target_source,
                        const PinholeCamera& camera);

}  // namespace ddl::camera
