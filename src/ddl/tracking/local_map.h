#pragma once
// The local map of tracking (ORB-SLAM2 Tracking::UpdateLocalMap / SearchLocalPoints, T-RO 2017
// section III-E "Track Local Map"):
//  - K1: the keyframes observing the frame's matched points; the one sharing most points becomes
//    the reference keyframe;
//  - K2: for each K1 keyframe its best not-yet-included covisible keyframe, child and parent,
//    while the set holds fewer than max_local_keyframes;
//  - local points: the distinct good map points of those keyframes.
// Local points not matched yet are projected into the frame (project_in_frustum) and matched by
// FrameMatcher::match_projections.
//
// All sets are built in a deterministic order (K1 by keyframe id, then the order above; points by
// keyframe then feature index). Visited marks are kept here, never on the shared entities.
// Owned by the tracking thread.

#include <cstddef>
#include <vector>

#include "ddl/map/keyframe.h"
#include "ddl/map/map_point.h"
#include "ddl/tracking/frame.h"
#include "ddl/tracking/frame_matching.h"
#include "ddl/tracking/id_marks.h"
#include "ddl/tracking/tracker_config.h"

namespace ddl::tracking {

class LocalMap {
 public:
  explicit LocalMap(const MatchingConfig& config) : config_(config) {}

  /// Rebuilds the local keyframes and points around the frame's matched points. Returns the
  /// keyframe sharing most points with the frame (the new reference keyframe), or nullptr when
  /// the frame observes no keyframe's points.
  map::KeyFramePtr update(const Frame& frame);

  /// Projects the local points the frame has not matched (nor rejected) into it and matches them
  /// (radius_factor: 3 for RGB-D, 5 just after a relocalization). Counts a "visible" for every
  /// point the frame already holds and every point predicted in view (ORB-SLAM2's found ratio).
  /// Returns the number of new matches.
  int search(Frame& frame, float radius_factor, FrameMatcher& matcher);

  const std::vector<map::KeyFramePtr>& keyframes() const { return keyframes_; }
  const std::vector<map::MapPointPtr>& points() const { return points_; }
  /// Local points predicted in view by the last search().
  std::size_t projected_count() const { return projections_.size(); }
  void clear();

 private:
  void collect_keyframes(const Frame& frame, map::KeyFramePtr& reference);
  void collect_points();

  MatchingConfig config_;
  std::vector<map::KeyFramePtr> keyframes_;
  std::vector<map::MapPointPtr> points_;
  std::vector<PointProjection> projections_;
  IdMarks keyframe_marks_;
  IdMarks point_marks_;
  std::vector<std::pair<map::KeyFrameId, int>> votes_;
  std::vector<map::KeyFramePtr> vote_keyframes_;
};

}  // namespace ddl::tracking
