#pragma once
// Keyframe-to-keyframe matching of local mapping (ORB-SLAM2 ORBmatcher::SearchForTriangulation
// and ORBmatcher::Fuse; Mur-Artal & Tardos, T-RO 2017, section V / ORB-SLAM T-RO 2015, VI-D, VI-E).
// Both also serve loop closing (fusion of the loop points at the corrected pose).
// Thread-safety: any thread; entities are read and changed only through their locked methods.

#include <cstddef>
#include <span>
#include <vector>

#include "ddl/map/keyframe.h"
#include "ddl/map/map.h"
#include "ddl/mapping/keyframe_geometry.h"
#include "ddl/mapping/local_mapper_config.h"

namespace ddl::mapping {

/// A candidate pair of unmatched features (index1 in keyframe 1, index2 in keyframe 2).
struct FeaturePair {
  std::size_t index1 = 0;
  std::size_t index2 = 0;
  friend bool operator==(const FeaturePair&, const FeaturePair&) = default;
};

/// Matches the features of kf1 and kf2 that have no map point yet, comparing only features under
/// the same vocabulary node (direct index; both keyframes need their BoW), keeping for each feature
/// of kf1 the nearest feature of kf2 within config.max_hamming that lies within
/// sqrt(epipolar_chi2) sigma of the epipolar line of the current poses (and, for two features
/// without depth, not next to the epipole). Each feature of kf2 is used once. Ordered by index1.
std::vector<FeaturePair> search_for_triangulation(const map::KeyFrame& kf1,
                                                  const map::KeyFrame& kf2,
                                                  const CameraIntrinsics& camera,
                                                  const TriangulationConfig& config);

/// What fuse() does when the matched feature already has a map point.
enum class FuseConflict {
  kKeepMostObserved,  // local mapping: the point with more observations absorbs the other
  kPreferProjected,   // loop closing: the projected (loop) point replaces the keyframe's point
};

struct FuseParams {
  double radius_factor = 3.0;      // window = radius_factor * scale factor of the predicted level
  int max_hamming = 50;            // best descriptor distance at most (TH_LOW)
  bool check_reprojection = true;  // chi2 test of the keypoint against the projection
  double chi2_mono = 5.991;
  double chi2_stereo = 7.8;
  double min_view_cos = 0.5;  // skip points viewed too far off their mean viewing direction
  FuseConflict conflict = FuseConflict::kKeepMostObserved;
};

/// Projects `points` into `keyframe` at pose T_c_w (the keyframe's own pose in local mapping, the
/// corrected pose in loop closing) and, for the best matching keypoint, either merges the point
/// with the keyframe's point there (points replaced are removed from `map`) or adds the point as a
/// new observation. Points that are null, bad or already observed by the keyframe are skipped.
/// Returns the number of fusions and added observations.
int fuse(const map::KeyFramePtr& keyframe, const SE3& T_c_w,
         std::span<const map::MapPointPtr> points, const CameraIntrinsics& camera,
         const FuseParams& params, map::Map& map);

}  // namespace ddl::mapping
