#pragma once
// Matching for loop verification (ORB-SLAM2 ORBmatcher::SearchByBoW between two keyframes and
// ORBmatcher::SearchByProjection of map points into a keyframe at a given pose).
// Thread-safety: any thread; entities are read through their locked methods.

#include <span>
#include <vector>

#include "ddl/map/keyframe.h"
#include "ddl/mapping/keyframe_geometry.h"

namespace ddl::loop {

/// Matches the map points of kf1 and kf2 through their features under the same vocabulary node:
/// for each feature of kf1 with a good point, the nearest feature of kf2 with a good point, kept
/// when its distance is < max_hamming and < ratio * the second nearest, each feature of kf2 used
/// once, optionally filtered by rotation consistency. Returns one slot per feature of kf1: the
/// matched point of kf2, or null.
std::vector<map::MapPointPtr> search_by_bow(const map::KeyFrame& kf1, const map::KeyFrame& kf2,
                                            float ratio, int max_hamming, bool check_orientation);

/// Projects `points` into `keyframe` at pose T_c_w and matches each (not already in `matches`) to
/// the best free feature within radius_factor * scale of its predicted level (levels predicted-1
/// to predicted) with distance <= max_hamming. `matches` has one slot per feature of the keyframe
/// and is filled in place. Returns the number of new matches.
int search_by_projection(const map::KeyFrame& keyframe, const SE3& T_c_w,
                         std::span<const map::MapPointPtr> points,
                         std::vector<map::MapPointPtr>& matches,
                         const mapping::CameraIntrinsics& camera, double radius_factor,
                         int max_hamming);

}  // namespace ddl::loop
