// Relocalization (ORB-SLAM2 Tracking::Relocalization): what its projection searches leave out.

#include "ddl/tracking/relocalizer.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <set>
#include <utility>
#include <vector>

#include "ddl/map/map.h"
#include "ddl/tracking/frame_matching.h"
#include "ddl/tracking/pose_estimation.h"
#include "tracking_test_support.h"

namespace ddl::tracking {
namespace {

using testing::first_room_frame_at_truth;
using testing::room_sequence;

// Relocalization's first projection search must not match again the points that the pose
// optimisation rejected (ORB-SLAM2 keeps every PnP inlier in sFound). A keyframe of the same
// image offers each of its points at the keypoint it came from, so a rejected point left unmarked
// is matched straight back into the frame.
TEST(RelocalizerTest, TheFirstProjectionSearchSkipsThePointsTheOptimisationRejected) {
  Frame frame = first_room_frame_at_truth();
  ASSERT_GT(frame.size(), 300u);
  auto keyframe = std::make_shared<map::KeyFrame>(
      0, 0.0, std::make_shared<map::FrameFeatures>(frame.features()), frame.T_c_w());
  std::vector<map::MapPointPtr> points(frame.size());
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (!frame.has_depth(i)) continue;
    auto point = std::make_shared<map::MapPoint>(i, frame.unproject_w(i), keyframe);
    point->add_observation(keyframe, i, true);
    keyframe->set_map_point(i, point);
    point->compute_distinctive_descriptor();
    point->update_normal_and_depth();
    points[i] = point;
  }
  // The "PnP inliers": every third point; the optimisation then rejects every ninth.
  int held = 0;
  int rejected = 0;
  for (std::size_t i = 0; i < frame.size(); i += 3) {
    if (!points[i]) continue;
    frame.set_map_point(i, points[i]);
    const bool outlier = i % 9 == 0;
    frame.set_outlier(i, outlier);
    (outlier ? rejected : held) += 1;
  }
  ASSERT_GT(rejected, 30);
  discard_outliers(frame);
  ASSERT_EQ(frame.matched_count(), held);
  ASSERT_EQ(static_cast<int>(frame.rejected_points().size()), rejected);

  FrameMatcher matcher;
  IdMarks marks;
  Frame with_rejected = frame;
  mark_already_found(with_rejected, /*with_rejected=*/true, marks);
  const int found = matcher.match_keyframe_projection(with_rejected, *keyframe, marks, 10.0f, 100);
  Frame without_rejected = frame;
  mark_already_found(without_rejected, /*with_rejected=*/false, marks);
  const int found_again =
      matcher.match_keyframe_projection(without_rejected, *keyframe, marks, 10.0f, 100);

  // The points never matched are found (about two thirds of them); the rejected ones only when
  // they are not marked.
  EXPECT_GT(found, 200);
  for (std::size_t i = 0; i < with_rejected.size(); ++i) {
    const map::MapPointPtr& p = with_rejected.map_point(i);
    if (!p) continue;
    ASSERT_TRUE(p->id() % 9 != 0 || p->id() % 3 != 0) << "rejected point " << p->id();
  }
  EXPECT_GE(found_again, found + rejected * 8 / 10)
      << "found " << found << ", rejected " << rejected;
}

// What relocalization asks of its projection searches: the first, wide search leaves out every
// PnP inlier, those the optimisation rejected included (sFound); the second, narrow one leaves
// out the frame's current matches. A matcher that records each search, and an estimator that
// rejects every fourth match and reports inlier counts that lead through both searches, watch the
// real Relocalizer.
class RecordingMatcher final : public FrameMatcher {
 public:
  struct Search {
    std::uint64_t keyframe_id = 0;
    float radius_px = 0.0f;
    std::set<map::MapPointId> excluded;  // the keyframe's points marked as already found
    std::set<map::MapPointId> held;      // the frame's matches when the search starts
    std::set<map::MapPointId> rejected;  // the frame's rejected points then
  };
  int match_keyframe_projection(Frame& frame, const map::KeyFrame& keyframe,
                                const IdMarks& already_found, float radius_px,
                                int max_distance) override {
    Search s;
    s.keyframe_id = keyframe.id();
    s.radius_px = radius_px;
    for (const map::MapPointPtr& p : keyframe.map_points()) {
      if (p && already_found.is_marked(p->id())) s.excluded.insert(p->id());
    }
    for (const map::MapPointPtr& p : frame.map_points()) {
      if (p) s.held.insert(p->id());
    }
    s.rejected.insert(frame.rejected_points().begin(), frame.rejected_points().end());
    searches.push_back(std::move(s));
    return FrameMatcher::match_keyframe_projection(frame, keyframe, already_found, radius_px,
                                                   max_distance);
  }
  std::vector<Search> searches;
};

class SteeringEstimator final : public FramePoseEstimator {
 public:
  SteeringEstimator(const FrameGeometry& geometry, const optimization::OptimizerConfig& config,
                    std::vector<int> reported)
      : FramePoseEstimator(geometry, config), reported_(std::move(reported)) {}
  int optimize(Frame& frame) override {
    FramePoseEstimator::optimize(frame);
    int matched = 0;
    for (std::size_t i = 0; i < frame.size(); ++i) {
      if (frame.map_points()[i] && matched++ % 4 == 0) frame.set_outlier(i, true);
    }
    const std::size_t call = std::min(calls_++, reported_.size() - 1);
    return reported_[call];
  }

 private:
  std::vector<int> reported_;
  std::size_t calls_ = 0;
};

TEST(RelocalizerTest, EachProjectionSearchLeavesOutWhatORBSLAM2LeavesOut) {
  const TrackerConfig config = testing::test_tracker_config();
  const testing::SequenceRun run = testing::track_sequence(30, /*associate=*/true, config);
  ASSERT_GE(run.map->keyframe_count(), 2u);
  Relocalizer relocalizer(config.relocalization, config.frame.bow_levels_up, run.map,
                          testing::room_vocabulary(), run.database);

  FrameBuilder builder(testing::test_camera(), config.orb, config.frame);
  Frame frame = builder.build(room_sequence().frames[12], cv::Mat(), 100);
  RecordingMatcher matcher;
  // One short of success after PnP (the wide search) and after it (the narrow search), so each
  // search needs to add a single match; then success.
  const RelocalizationConfig& rc = config.relocalization;
  ASSERT_GT(rc.min_inliers - 1, rc.retry_inliers);
  ASSERT_GE(rc.min_inliers - 1, rc.pnp_min_inliers);
  SteeringEstimator estimator(*builder.geometry(), config.optimizer,
                              {rc.min_inliers - 1, rc.min_inliers - 1, rc.min_inliers});
  const RelocalizationResult result = relocalizer.relocalize(frame, matcher, estimator);
  ASSERT_TRUE(result.success);
  ASSERT_EQ(matcher.searches.size(), 2u);
  const RecordingMatcher::Search& wide = matcher.searches[0];
  const RecordingMatcher::Search& narrow = matcher.searches[1];
  EXPECT_EQ(wide.keyframe_id, result.keyframe->id());
  EXPECT_EQ(narrow.keyframe_id, result.keyframe->id());
  EXPECT_EQ(wide.radius_px, rc.search_radius_px);
  EXPECT_EQ(narrow.radius_px, rc.retry_radius_px);

  // Wide: the PnP inliers, held or rejected by the optimisation (all are the keyframe's points).
  ASSERT_FALSE(wide.rejected.empty());
  ASSERT_FALSE(wide.held.empty());
  std::set<map::MapPointId> pnp_inliers = wide.held;
  pnp_inliers.insert(wide.rejected.begin(), wide.rejected.end());
  EXPECT_EQ(wide.excluded, pnp_inliers);
  // Narrow: the current matches only. The points rejected after PnP are still remembered as
  // rejected (so marking them would show), but this search may find them again.
  EXPECT_EQ(narrow.rejected, wide.rejected);
  EXPECT_EQ(narrow.excluded, narrow.held);
}

}  // namespace
}  // namespace ddl::tracking
