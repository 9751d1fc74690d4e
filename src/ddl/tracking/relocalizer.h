#pragma once
// Relocalization (ORB-SLAM2 Tracking::Relocalization and KeyFrameDatabase::
// DetectRelocalizationCandidates; T-RO 2017 section III-D / "place recognition"):
//  1. candidates: keyframes of the BoW database sharing many words with the frame, scored with
//     their covisible neighbours, best of each good group;
//  2. per candidate: BoW matches, PnP RANSAC on the matched map points (OpenCV EPnP in a
//     deterministic RANSAC), motion-only BA;
//  3. too few inliers: more matches by projecting the candidate's points with the estimated pose
//     (wide, then narrow window), optimised again; success with min_inliers inliers.
// Owned by the tracking thread; reads the map and the database (both thread-safe).

#include <memory>
#include <vector>

#include "ddl/map/map.h"
#include "ddl/tracking/frame.h"
#include "ddl/tracking/frame_matching.h"
#include "ddl/tracking/id_marks.h"
#include "ddl/tracking/pose_estimation.h"
#include "ddl/tracking/tracker_config.h"
#include "ddl/vocabulary/bow_database.h"
#include "ddl/vocabulary/vocabulary.h"

namespace ddl::tracking {

struct RelocalizationResult {
  bool success = false;
  int inliers = 0;            // inliers of the final pose optimisation
  int candidates = 0;         // keyframes proposed by the database
  map::KeyFramePtr keyframe;  // the candidate that relocalized the frame
};

/// Starts a new round of `marks` and marks the map points the frame holds, and with
/// `with_rejected` also those its pose estimation rejected (Frame::rejected_points): the points a
/// projection search must not match again. ORB-SLAM2's relocalization excludes all PnP inliers
/// from its first projection search, those the pose optimisation then rejected included.
void mark_already_found(const Frame& frame, bool with_rejected, IdMarks& marks);

class Relocalizer {
 public:
  Relocalizer(const RelocalizationConfig& config, int bow_levels_up,
              std::shared_ptr<const map::Map> map,
              std::shared_ptr<const vocabulary::Vocabulary> vocabulary,
              std::shared_ptr<const vocabulary::BowDatabase> keyframe_database);

  /// Candidate keyframes for a BoW vector, best first (deterministic order).
  std::vector<map::KeyFramePtr> candidates(const vocabulary::BowVector& bow) const;

  /// Tries to find the frame's pose in the map. On success the frame holds the pose and its
  /// inlier matches; on failure its matches are cleared and its pose is undefined.
  RelocalizationResult relocalize(Frame& frame, FrameMatcher& matcher,
                                  FramePoseEstimator& estimator);

 private:
  /// PnP RANSAC on the BoW matches; sets the frame's pose and keeps only the RANSAC inliers.
  bool solve_pnp(Frame& frame, const std::vector<map::MapPointPtr>& matches);

  RelocalizationConfig config_;
  int bow_levels_up_;
  std::shared_ptr<const map::Map> map_;
  std::shared_ptr<const vocabulary::Vocabulary> vocabulary_;
  std::shared_ptr<const vocabulary::BowDatabase> database_;
  std::vector<map::MapPointPtr> matches_;
  IdMarks found_;
};

}  // namespace ddl::tracking
