// Relocalization (issue 4): a run of blank frames in the middle of a sequence makes tracking lose
// the camera; once the images come back, tracking relocalizes in the map built before the gap
// and the trajectory continues correctly.

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <map>

#include "ddl/pipeline/system.h"
#include "pipeline_test_support.h"

namespace ddl::pipeline {
namespace {

using testing::core_config;
using testing::default_vocabulary;

// syn_static_rpy's motion (rotations about a nearly fixed position, so the views after the gap
// show mapped parts of the room); frames kBlankBegin..kBlankEnd-1 are black with no depth.
constexpr int kFrames = 240;
constexpr std::size_t kBlankBegin = 150;
constexpr std::size_t kBlankEnd = 180;

TEST(Relocalization, RecoversAfterBlankFramesAndContinuesOnTheTrueTrajectory) {
  const auto vocabulary = default_vocabulary();
  if (!vocabulary) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const auto source =
      synthetic::make_sequence_source(testing::preset_config("syn_static_rpy", kFrames));
  const camera::PinholeCamera& camera = source->camera();
  const SystemConfig config = core_config();
  System system(config, camera, vocabulary);

  std::size_t keyframes_before_gap = 0;
  std::size_t lost_in_gap = 0;
  std::size_t first_recovered = 0;
  std::map<double, SE3> truth;  // by timestamp
  for (std::size_t i = 0; i < source->frame_count(); ++i) {
    const synthetic::FrameData data = source->render_frame(i);
    truth[data.rgb_stamp_s] = data.T_w_c;
    io::RgbdFrame frame = testing::to_rgbd(data, camera);
    const bool blank = i >= kBlankBegin && i < kBlankEnd;
    if (blank) {
      frame.rgb.setTo(cv::Scalar::all(0));
      frame.depth_m.setTo(0.0f);
    }
    if (i == kBlankBegin) keyframes_before_gap = system.statistics().keyframes;
    const FrameOutcome outcome = system.process(frame);
    if (blank && outcome.tracking.state == tracking::TrackingState::kLost) ++lost_in_gap;
    if (!blank && i >= kBlankEnd && first_recovered == 0 && outcome.tracking.tracked()) {
      first_recovered = i;
    }
  }
  system.finish();
  const SystemStatistics stats = system.statistics();
  std::printf(
      "%zu keyframes before the gap, %zu of %zu blank frames lost, relocalized at frame %zu "
      "(%zu relocalizations), %zu map resets\n",
      keyframes_before_gap, lost_in_gap, kBlankEnd - kBlankBegin, first_recovered,
      stats.relocalizations, stats.map_resets);

  // Precondition: the map is big enough that the tracker keeps it when lost (no reset).
  ASSERT_GT(keyframes_before_gap,
            static_cast<std::size_t>(config.tracking.reset_when_lost_max_keyframes));
  EXPECT_EQ(lost_in_gap, kBlankEnd - kBlankBegin);
  EXPECT_EQ(stats.map_resets, 0u);
  EXPECT_GE(stats.relocalizations, 1u);
  ASSERT_GT(first_recovered, 0u) << "tracking never recovered";
  EXPECT_LE(first_recovered, kBlankEnd + 15) << "relocalization took too long";

  // The map's world is the first frame's camera: compare every tracked pose with the true pose
  // relative to frame 0, before the gap and after the recovery alike.
  const SE3 T_c0_w = truth.begin()->second.inverse();
  double worst_before_m = 0.0;
  double worst_after_m = 0.0;
  double worst_after_deg = 0.0;
  std::size_t tracked_after = 0;
  const double gap_end_s = truth.begin()->first + kBlankEnd / camera.fps - 1e-3;
  for (const io::StampedPose& pose : system.camera_trajectory()) {
    const auto it = truth.find(pose.timestamp_s);
    ASSERT_NE(it, truth.end()) << "no frame at stamp " << pose.timestamp_s;
    const testing::PoseError error = testing::pose_error(pose.T_w_c(), T_c0_w * it->second);
    if (pose.timestamp_s < gap_end_s) {
      worst_before_m = std::max(worst_before_m, error.translation_m);
    } else {
      ++tracked_after;
      worst_after_m = std::max(worst_after_m, error.translation_m);
      worst_after_deg = std::max(worst_after_deg, error.rotation_deg);
    }
  }
  std::printf("worst error before the gap %.4f m; after it %.4f m, %.3f deg (%zu frames)\n",
              worst_before_m, worst_after_m, worst_after_deg, tracked_after);
  EXPECT_EQ(tracked_after, kFrames - first_recovered);
  EXPECT_LT(worst_after_m, 0.03);
  EXPECT_LT(worst_after_deg, 1.5);
}

// Lost with a young map, tracking resets it and starts a new world frame. Every stage must
// follow: the octree holds only the keyframes made after the reset (before 2026-11-26 the dense
// stage kept the old ones, in a frame that no longer exists).
TEST(Relocalization, AMapResetRestartsTheDenseMapToo) {
  const auto vocabulary = default_vocabulary();
  if (!vocabulary) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  const auto source = synthetic::make_sequence_source(testing::preset_config("syn_static_xyz", 60));
  const camera::PinholeCamera& camera = source->camera();
  SystemConfig config = core_config();
  config.dense.octomap_enabled = true;
  config.dense.inpainting_enabled = true;
  System system(config, camera, vocabulary);
  std::size_t keyframes_after_reset = 0;
  bool reset_seen = false;
  for (std::size_t i = 0; i < source->frame_count(); ++i) {
    io::RgbdFrame frame = testing::to_rgbd(source->render_frame(i), camera);
    if (i >= 12 && i < 15) {  // blank frames while the map has a handful of keyframes
      frame.rgb.setTo(cv::Scalar::all(0));
      frame.depth_m.setTo(0.0f);
    }
    const FrameOutcome outcome = system.process(frame);
    if (outcome.tracking.map_reset) {
      reset_seen = true;
      keyframes_after_reset = 0;
    }
    if (reset_seen && outcome.tracking.new_keyframe) ++keyframes_after_reset;
  }
  system.finish();
  const SystemStatistics stats = system.statistics();
  ASSERT_TRUE(reset_seen) << "precondition: the blank frames reset the young map";
  EXPECT_EQ(stats.dense.resets, stats.map_resets);
  ASSERT_GT(keyframes_after_reset, 0u);
  ASSERT_NE(system.dense_mapper().octree(), nullptr);
  EXPECT_EQ(system.dense_mapper().octree()->stats().scans_integrated, keyframes_after_reset);
}

// The camera jumps from frame 100 of syn_static_rpy back to the view of frame 5, 53 degrees away:
// tracking and the low-cost pose fail on that frame, and it is relocalized at once
// (tracking.relocalization.same_frame). With dynamic removal on (geometry check only), the
// geometry check ran at the constant-velocity prediction that failed; its mask must not reach the
// frame's combined mask, which the keyframe and the dense map take (review, stop 29).
TEST(Relocalization, AFrameRelocalizedAtOnceKeepsNoMaskOfTheFailedPrediction) {
  const auto vocabulary = default_vocabulary();
  if (!vocabulary) GTEST_SKIP() << "vocab/ddl_orb_k10_l5.dvoc is absent";
  constexpr std::size_t kJumpFrom = 100;
  constexpr std::size_t kJumpTo = 5;
  const auto source =
      synthetic::make_sequence_source(testing::preset_config("syn_static_rpy", kJumpFrom + 1));
  const camera::PinholeCamera& camera = source->camera();
  SystemConfig config = core_config();
  config.dynamic.enabled = true;
  config.dynamic.segmentation.backend = segmentation::Backend::kNone;  // geometry checks alone
  config.dynamic.use_geometry = true;  // the sparse check beside the free-space one
  ASSERT_TRUE(config.dynamic.free_space.enabled);
  ASSERT_TRUE(config.tracking.relocalization.same_frame);
  System system(config, camera, vocabulary);
  double stamp = 0.0;
  for (std::size_t i = 0; i <= kJumpFrom; ++i) {
    const io::RgbdFrame frame = testing::to_rgbd(source->render_frame(i), camera);
    stamp = frame.timestamp_s;
    ASSERT_TRUE(system.process(frame).tracking.tracked()) << "frame " << i;
  }
  const synthetic::FrameData back = source->render_frame(kJumpTo);
  io::RgbdFrame jump = testing::to_rgbd(back, camera);
  jump.index = kJumpFrom + 1;
  jump.timestamp_s = stamp + 1.0 / camera.fps;
  const FrameOutcome outcome = system.process(jump);
  ASSERT_EQ(outcome.tracking.state, tracking::TrackingState::kRelocalized);
  EXPECT_TRUE(outcome.tracking.relocalized_at_once);
  EXPECT_EQ(system.statistics().relocalizations_in_same_frame, 1u);
  EXPECT_EQ(system.statistics().frames_lost, 0u);
  // The geometry checks ran at the failed prediction and found seeds there; their masks (and
  // with them what the keyframe and the dense map would take from the combined mask) were
  // discarded.
  EXPECT_GT(outcome.masks.geometry_stats.points_tested, 0);
  EXPECT_GT(outcome.masks.geometry_stats.points_dynamic, 0);
  EXPECT_TRUE(outcome.masks.geometry.empty());
  EXPECT_GT(outcome.masks.free_space_stats.samples_dynamic, 0);  // the same for the free space
  EXPECT_TRUE(outcome.masks.free_space.empty());
  EXPECT_TRUE(outcome.masks.free_space_votes.free_votes.empty());
  EXPECT_TRUE(outcome.masks.combined.empty() || cv::countNonZero(outcome.masks.combined) == 0);
  // The pose: frame 5's, in the map's world (frame 0's camera).
  const SE3 T_c0_w = source->render_frame(0).T_w_c.inverse();
  ASSERT_TRUE(outcome.tracking.T_w_c.has_value());
  const testing::PoseError e = testing::pose_error(*outcome.tracking.T_w_c, T_c0_w * back.T_w_c);
  EXPECT_LT(e.translation_m, 0.02);
  EXPECT_LT(e.rotation_deg, 1.0);
  system.finish();
}

}  // namespace
}  // namespace ddl::pipeline
