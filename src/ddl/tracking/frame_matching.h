#pragma once
// Map-aware matching for tracking (ORB-SLAM2 ORBmatcher, the searches tracking uses):
//  - projection of the last frame's points into the current frame at the motion-model pose;
//  - projection of local map points (visibility predicted by project_in_frustum);
//  - BoW matching of a frame against a keyframe (reference-keyframe tracking, relocalization);
//  - projection of a keyframe's points into a frame (relocalization refinement).
// Candidates come from the frame's FeatureGrid; descriptors are compared by Hamming distance and
// orientation consistency is checked with the rotation histogram (features/matcher.h).
//
// A FrameMatcher holds scratch buffers only (no state between calls), so one instance serves one
// thread. Results depend only on the inputs (deterministic).

#include <cstddef>
#include <cstdint>
#include <vector>

#include "ddl/features/matcher.h"
#include "ddl/map/keyframe.h"
#include "ddl/map/map_point.h"
#include "ddl/tracking/frame.h"
#include "ddl/tracking/id_marks.h"

namespace ddl::tracking {

/// Where a map point is expected in a frame (ORB-SLAM2 Frame::isInFrustum outputs).
struct PointProjection {
  map::MapPointPtr point;
  float u = 0.0f;  // predicted pixel
  float v = 0.0f;
  float u_right = 0.0f;   // predicted virtual right coordinate u - bf / z
  int level = 0;          // predicted pyramid level from the distance
  float view_cos = 0.0f;  // cosine between the viewing ray and the point's mean viewing direction
};

/// Predicts whether `point` is visible in `frame` (pose set): in front of the camera, inside the
/// image, within the point's scale-invariance distance range and seen at most acos(min_view_cos)
/// away from its mean viewing direction. Fills `out` and returns true when visible.
bool project_in_frustum(const Frame& frame, const map::MapPointPtr& point, float min_view_cos,
                        PointProjection& out);

/// The searches are virtual so that a test can watch what a caller asks of them (relocalization's
/// exclusion sets); the tracker uses this class as it is.
class FrameMatcher {
 public:
  virtual ~FrameMatcher() = default;

  /// ORB-SLAM2 SearchByProjection(Frame, LastFrame): each inlier point of `last` (pose known) is
  /// projected into `current` (pose = prediction); the search window is radius_px scaled by the
  /// keypoint's level, restricted to finer / coarser levels when the camera moved forward /
  /// backward by more than the baseline. Best match within TH_HIGH, then rotation consistency.
  /// Fills current's empty slots (or slots holding points without observations, unless this
  /// search filled them). Points of `last` that local mapping culled meanwhile are skipped
  /// (ORB-SLAM2 keeps a culled point's observation count, so its slot stays protected there).
  /// Returns the number of matches, each in its own slot.
  int match_last_frame(Frame& current, const Frame& last, float radius_px);

  /// ORB-SLAM2 SearchByProjection(Frame, vector<MapPoint*>): matches the projected local points
  /// into free slots of `frame`. Window: radius_factor * (2.5 if viewed head-on, else 4) * level
  /// scale, levels [level - 1, level]; best within TH_HIGH, ratio test `ratio` when the two best
  /// are on the same level. Returns the number of matches.
  int match_projections(Frame& frame, const std::vector<PointProjection>& projections,
                        float radius_factor, float ratio);

  /// ORB-SLAM2 SearchByBoW(KeyFrame, Frame): features sharing a vocabulary node (direct index at
  /// the same level) are compared; best within TH_LOW and below ratio * second best, then
  /// rotation consistency. `matches` gets frame.size() slots, the keyframe's point in each
  /// matched one. Both must have BoW computed. Returns the number of matches.
  virtual int match_bow(const map::KeyFrame& keyframe, const Frame& frame, float ratio,
                        std::vector<map::MapPointPtr>& matches);

  /// ORB-SLAM2 SearchByProjection(Frame, KeyFrame, sAlreadyFound, th, ORBdist): projects the
  /// keyframe's points not in `already_found` (map point ids marked in that IdMarks round) into
  /// empty slots of `frame`; window radius_px * level scale over levels [l - 1, l + 1], best
  /// within max_distance, rotation consistency. Returns the number of matches.
  virtual int match_keyframe_projection(Frame& frame, const map::KeyFrame& keyframe,
                                        const IdMarks& already_found, float radius_px,
                                        int max_distance);

 private:
  /// Applies the rotation-consistency check to the matches recorded in histogram_ (ids = frame
  /// slot indices): discards the inconsistent ones from `frame`. Returns how many were dropped.
  int drop_inconsistent_rotations(Frame& frame);

  std::vector<std::size_t> candidates_;
  features::RotationHistogram histogram_;
  // Slots filled by the running match_last_frame: taken even if their point went bad meanwhile,
  // so that every histogram entry still names the point in its slot.
  std::vector<std::uint8_t> filled_;
};

}  // namespace ddl::tracking
