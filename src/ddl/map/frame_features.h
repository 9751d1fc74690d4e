#pragma once
// The features of one RGB-D frame, immutable once built and shared (shared_ptr<const>) between
// the tracking frame and the keyframe made from it (ARCHITECTURE.md section 3).

#include <opencv2/core.hpp>
#include <vector>

#include "ddl/core/types.h"
#include "ddl/features/feature_grid.h"
#include "ddl/features/orb_extractor.h"
#include "ddl/vocabulary/bow_vector.h"

namespace ddl::map {

struct FrameFeatures {
  std::vector<cv::KeyPoint> keypoints;  // undistorted, level-0 pixels; octave = pyramid level
  cv::Mat descriptors;                  // keypoints.size() x 32, CV_8U
  features::ScalePyramid pyramid;       // per-level scale and information weights
  std::vector<float> depth_m;           // depth at each keypoint, metres; 0 = no measurement
  std::vector<float> u_right;           // virtual right-image u = u - bf / depth; < 0 = none
  features::FeatureGrid grid;           // spatial index over keypoints
  vocabulary::BowVector bow;            // empty until computed (keyframes, relocalization)
  vocabulary::FeatureVector feature_vector;

  std::size_t size() const { return keypoints.size(); }
  bool has_depth(std::size_t i) const { return depth_m[i] > 0.0f; }
  /// Whether feature i enters the optimisers with its depth row (u, v, u_right): ORB-SLAM2's
  /// u_right >= 0, so a close point left of u = bf / depth has its 2-dof residual only (the
  /// depth row there was measured worse, docs/optimization.md). The one rule for tracking and
  /// mapping.
  bool is_stereo(std::size_t i) const { return !u_right.empty() && u_right[i] >= 0.0f; }
  bool has_bow() const { return !bow.empty(); }
};

}  // namespace ddl::map
