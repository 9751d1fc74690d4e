#include "ddl/tracking/tracker.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "ddl/core/error.h"
#include "tracking_test_support.h"

namespace ddl::tracking {
namespace {

using testing::associate_keyframe;
using testing::pose_error;
using testing::room_sequence;
using testing::SequenceRun;
using testing::track_sequence;

/// Ground truth of frame k expressed in the first camera's frame (the map's world frame).
SE3 truth_in_map(std::size_t k) {
  const auto& seq = room_sequence();
  return seq.T_w_c[0].inverse() * seq.T_w_c[k];
}

/// A tracker on an empty map of the room (no local mapping: the tests feed it frames by hand).
std::unique_ptr<Tracker> room_tracker(const TrackerConfig& config) {
  return std::make_unique<Tracker>(config, testing::test_camera(), std::make_shared<map::Map>(),
                                   testing::room_vocabulary(),
                                   std::make_shared<vocabulary::BowDatabase>());
}

/// The pose of tracking result `r` for room frame k is within 1 cm and 0.5 degrees of the truth.
void expect_near_truth(const TrackingResult& r, std::size_t k) {
  const testing::PoseError e = pose_error(*r.T_w_c, truth_in_map(k));
  EXPECT_LT(e.translation_m, 0.01) << "frame " << k;
  EXPECT_LT(e.rotation_deg, 0.5) << "frame " << k;
}

void expect_accurate(const SequenceRun& run, std::size_t count) {
  ASSERT_EQ(run.results.size(), count);
  EXPECT_EQ(run.results[0].method, TrackingMethod::kInitialization);
  ASSERT_EQ(run.trajectory.size(), count);
  double worst_t = 0.0;
  double worst_r = 0.0;
  for (std::size_t k = 0; k < count; ++k) {
    const TrackingResult& r = run.results[k];
    ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << k;
    ASSERT_TRUE(r.T_w_c.has_value());
    EXPECT_GE(r.num_inliers, 100) << "frame " << k;
    const testing::PoseError e = pose_error(*r.T_w_c, truth_in_map(k));
    const testing::PoseError e_traj = pose_error(run.trajectory[k].T_w_c(), truth_in_map(k));
    worst_t = std::max({worst_t, e.translation_m, e_traj.translation_m});
    worst_r = std::max({worst_r, e.rotation_deg, e_traj.rotation_deg});
    EXPECT_LT(e.translation_m, 0.01) << "frame " << k;
    EXPECT_LT(e.rotation_deg, 0.5) << "frame " << k;
    EXPECT_LT(e_traj.translation_m, 0.01) << "frame " << k;
    EXPECT_LT(e_traj.rotation_deg, 0.5) << "frame " << k;
  }
  std::printf("worst error over %zu frames: %.2f mm, %.3f deg\n", count, worst_t * 1000.0, worst_r);
}

TEST(TrackerTest, TracksSyntheticSequenceWithMapFromTrackerOnly) {
  const SequenceRun run = track_sequence(30, /*associate=*/false, testing::test_tracker_config());
  expect_accurate(run, 30);
  // Frames after the second use the constant-velocity model.
  int motion_model = 0;
  for (const auto& r : run.results) motion_model += r.method == TrackingMethod::kMotionModel;
  EXPECT_GE(motion_model, 20);
  EXPECT_GE(run.keyframes_created, 2u);
  EXPECT_EQ(run.map->keyframe_count(), run.keyframes_created);
}

TEST(TrackerTest, KeypointStatusesAreTheFramesKeypointsAndItsInlierMatches) {
  const SequenceRun run = track_sequence(20, /*associate=*/true, testing::test_tracker_config());
  for (const TrackingResult& r : run.results) {
    ASSERT_EQ(r.keypoints.size(), r.num_features) << "frame " << r.frame_index;
    const auto matched = static_cast<int>(std::count_if(
        r.keypoints.begin(), r.keypoints.end(), [](const KeypointStatus& k) { return k.matched; }));
    // The inliers of the pose, also on keyframe frames (whose new close points are not matches),
    // and none on the initialising frame.
    if (r.method == TrackingMethod::kInitialization) {
      EXPECT_EQ(matched, 0) << "frame " << r.frame_index;
    } else {
      EXPECT_EQ(matched, r.num_inliers) << "frame " << r.frame_index;
    }
    const camera::PinholeCamera camera = testing::test_camera();
    for (const KeypointStatus& k : r.keypoints) {
      ASSERT_TRUE(k.u >= 0.0f && k.u < camera.width && k.v >= 0.0f && k.v < camera.height);
    }
  }
}

TEST(TrackerTest, TracksSyntheticSequenceWithKeyframeAssociation) {
  const SequenceRun run = track_sequence(40, /*associate=*/true, testing::test_tracker_config());
  expect_accurate(run, 40);
  EXPECT_GE(run.keyframes_created, 3u);
  // Keyframes are linked in the covisibility graph and the spanning tree.
  for (const map::KeyFramePtr& kf : run.map->keyframes()) {
    if (kf->id() == 0) continue;
    EXPECT_TRUE(kf->parent()) << "keyframe " << kf->id();
    EXPECT_FALSE(kf->covisibles().empty()) << "keyframe " << kf->id();
  }
}

TEST(TrackerTest, SameInputGivesIdenticalTrajectory) {
  const SequenceRun a = track_sequence(20, true, testing::test_tracker_config());
  const SequenceRun b = track_sequence(20, true, testing::test_tracker_config());
  ASSERT_EQ(a.trajectory.size(), b.trajectory.size());
  for (std::size_t k = 0; k < a.trajectory.size(); ++k) {
    EXPECT_EQ(a.trajectory[k].timestamp_s, b.trajectory[k].timestamp_s);
    EXPECT_EQ(a.trajectory[k].t_w_c, b.trajectory[k].t_w_c) << "frame " << k;
    EXPECT_EQ(a.trajectory[k].q_xyzw, b.trajectory[k].q_xyzw) << "frame " << k;
    EXPECT_EQ(a.results[k].num_inliers, b.results[k].num_inliers) << "frame " << k;
  }
  EXPECT_EQ(a.map->map_point_count(), b.map->map_point_count());
  EXPECT_EQ(a.keyframes_created, b.keyframes_created);
}

TEST(TrackerTest, MotionModelSpansDroppedFrames) {
  // Frames 0-14, then 21-39: the velocity is scaled to the seven intervals of the gap (ORB-SLAM2
  // would predict one interval's motion, miss the matches and fall back on the reference
  // keyframe), and back to one interval for frame 22; the motion prior widens across the gap.
  const TrackerConfig config = testing::test_tracker_config();
  ASSERT_TRUE(config.motion_prior.enabled);
  const std::unique_ptr<Tracker> tracker = room_tracker(config);
  const MappingStatus idle;
  for (std::size_t k = 0; k < room_sequence().frames.size(); ++k) {
    if (k >= 15 && k <= 20) continue;
    const TrackingResult r = tracker->track(room_sequence().frames[k], cv::Mat(), idle);
    ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << k;
    if (k == 21) {
      EXPECT_EQ(r.method, TrackingMethod::kMotionModel);
    }
    expect_near_truth(r, k);
  }
}

TEST(TrackerTest, AGlitchedStampDoesNotStretchTheVelocity) {
  // Frame 10 is stamped 1 ms after frame 9 (a driver's glitch; the camera moved a whole
  // interval). The velocity learnt from frames 9-10 would be stretched 65-fold to frame 11 if its
  // 1 ms were taken at face value; as a glitch it repeats once and the motion model tracks
  // frame 11.
  const std::unique_ptr<Tracker> tracker = room_tracker(testing::test_tracker_config());
  const MappingStatus idle;
  for (std::size_t k = 0; k < 20; ++k) {
    io::RgbdFrame frame = room_sequence().frames[k];
    if (k == 10) frame.timestamp_s = room_sequence().frames[9].timestamp_s + 0.001;
    const TrackingResult r = tracker->track(frame, cv::Mat(), idle);
    ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << k;
    if (k >= 2) {
      EXPECT_EQ(r.method, TrackingMethod::kMotionModel) << "frame " << k;
    }
    expect_near_truth(r, k);
  }
}

TEST(TrackerTest, TheMotionPriorJoinsOnlyMotionModelTracking) {
  // Frame 1 has no velocity yet and is tracked against the reference keyframe, without a prior;
  // later frames by the motion model, with it; none with the prior switched off.
  for (const bool enabled : {true, false}) {
    TrackerConfig config = testing::test_tracker_config();
    config.motion_prior.enabled = enabled;
    const testing::SequenceRun run = testing::track_sequence(12, false, config);
    std::size_t with_prior = 0;
    for (std::size_t k = 1; k < run.results.size(); ++k) {
      const TrackingResult& r = run.results[k];
      ASSERT_TRUE(r.tracked()) << "frame " << k;
      if (k == 1) {
        EXPECT_EQ(r.method, TrackingMethod::kReferenceKeyFrame);
      }
      EXPECT_EQ(r.motion_prior_used, enabled && r.method == TrackingMethod::kMotionModel)
          << "frame " << k << (enabled ? ", prior on" : ", prior off");
      with_prior += r.motion_prior_used ? 1 : 0;
    }
    EXPECT_EQ(with_prior, enabled ? run.results.size() - 2 : 0u);
  }
}

TEST(TrackerTest, NoMotionPriorAfterTheMotionModelFailed) {
  // Frames 0-5, then frame 20 stamped one interval after frame 5: the constant-velocity
  // prediction is far off, its search finds too few matches, and the reference keyframe tracks
  // the frame, without the prior the failed attempt had set.
  constexpr std::size_t kJump = 20;
  const std::unique_ptr<Tracker> tracker = room_tracker(testing::test_tracker_config());
  const MappingStatus idle;
  for (std::size_t k = 0; k <= 5; ++k) {
    ASSERT_TRUE(tracker->track(room_sequence().frames[k], cv::Mat(), idle).tracked());
  }
  io::RgbdFrame jump = room_sequence().frames[kJump];
  jump.index = 6;
  jump.timestamp_s = room_sequence().frames[6].timestamp_s;
  const TrackingResult r = tracker->track(std::move(jump), cv::Mat(), idle);
  ASSERT_TRUE(r.tracked());
  EXPECT_EQ(r.method, TrackingMethod::kReferenceKeyFrame);
  EXPECT_FALSE(r.motion_prior_used);
  expect_near_truth(r, kJump);
}

TEST(TrackerTest, AbruptSpeedChangesAreTrackedDespiteTheMotionPrior) {
  // Frames 0-14, then every third frame up to 30, then every frame, stamped at a steady 30 Hz: the
  // camera triples its speed within one interval and drops back (no timestamp gap tells). The
  // constant-velocity prediction, and with it the prior, is then off by two intervals' motion; the
  // matches must outweigh the prior (docs/tracking.md, "Abrupt speed changes").
  const TrackerConfig config = testing::test_tracker_config();
  ASSERT_TRUE(config.motion_prior.enabled);
  const std::unique_ptr<Tracker> tracker = room_tracker(config);
  const MappingStatus idle;
  std::vector<std::size_t> fed;
  for (std::size_t k = 0; k < room_sequence().frames.size(); k += (k >= 15 && k < 30) ? 3 : 1) {
    fed.push_back(k);
  }
  const double t0 = room_sequence().frames[0].timestamp_s;
  for (std::size_t i = 0; i < fed.size(); ++i) {
    const std::size_t k = fed[i];
    io::RgbdFrame frame = room_sequence().frames[k];
    frame.index = i;
    frame.timestamp_s = t0 + static_cast<double>(i) / 30.0;
    const TrackingResult r = tracker->track(std::move(frame), cv::Mat(), idle);
    ASSERT_EQ(r.state, TrackingState::kOk) << "frame " << k;
    if (i > 1) {
      EXPECT_EQ(r.method, TrackingMethod::kMotionModel) << "frame " << k;
    }
    // Measured: at most 4.1 mm and 0.10 degrees (frame 27, in the fast stretch; 2.3 mm and
    // 0.05 degrees without the prior). A prior five times as tight (1 mm, 0.2 degrees) is off by
    // 14-17 cm from frame 27 on.
    expect_near_truth(r, k);
  }
}

TEST(TrackerTest, LowCostPoseIsCloseToGroundTruth) {
  // DDL-SLAM Algorithm 1 with the split API: features once, the low-cost pose (last-frame
  // matching and motion-only BA, no local map), features of a "moving" region dropped, then the
  // rest of tracking on the same frame.
  auto map = std::make_shared<map::Map>();
  auto database = std::make_shared<vocabulary::BowDatabase>();
  Tracker tracker(testing::test_tracker_config(), testing::test_camera(), map,
                  testing::room_vocabulary(), database);
  cv::Mat moving(480, 640, CV_8U, cv::Scalar(0));
  moving(cv::Rect(260, 140, 120, 200)).setTo(255);
  const MappingStatus idle;
  double worst_t = 0.0;
  double worst_r = 0.0;
  constexpr std::size_t kFrames = 25;
  for (std::size_t k = 0; k < kFrames; ++k) {
    Frame frame = tracker.prepare_frame(room_sequence().frames[k], cv::Mat());
    const std::size_t extracted = frame.size();
    const std::optional<SE3> T_c_w = tracker.low_cost_pose(frame);
    if (k == 0) {
      EXPECT_FALSE(T_c_w) << "no map before the first frame";
    } else {
      ASSERT_TRUE(T_c_w) << "frame " << k;
      const testing::PoseError e = pose_error(T_c_w->inverse(), truth_in_map(k));
      worst_t = std::max(worst_t, e.translation_m);
      worst_r = std::max(worst_r, e.rotation_deg);
      // Measured: at most 2.7 mm and 0.06 degrees; the bounds leave a wide margin.
      EXPECT_LT(e.translation_m, 0.01) << "frame " << k;
      EXPECT_LT(e.rotation_deg, 0.5) << "frame " << k;
    }
    const std::size_t dropped = tracker.exclude_features(frame, moving);
    EXPECT_GT(dropped, 20u) << "frame " << k;
    EXPECT_EQ(frame.size(), extracted - dropped);
    const TrackingResult r = tracker.track(std::move(frame), idle);
    ASSERT_TRUE(r.tracked()) << "frame " << k;
    EXPECT_EQ(r.num_features, extracted - dropped);
    if (k >= 2) {
      EXPECT_EQ(r.method, TrackingMethod::kMotionModel) << "frame " << k;
    }
    if (r.new_keyframe) associate_keyframe(r.new_keyframe, *database);
    EXPECT_LT(pose_error(*r.T_w_c, truth_in_map(k)).translation_m, 0.01) << "frame " << k;
    for (const cv::KeyPoint& kp : tracker.last_frame().features().keypoints) {
      ASSERT_EQ(moving.at<std::uint8_t>(cv::Point(static_cast<int>(std::lround(kp.pt.x)),
                                                  static_cast<int>(std::lround(kp.pt.y)))),
                0);
    }
  }
  std::printf("low-cost pose, worst error over %zu frames: %.2f mm, %.3f deg\n", kFrames - 1,
              worst_t * 1000.0, worst_r);
}

// Review finding (stop 14, threaded mode): loop closing may move the map between
// low_cost_pose() and track(). The low-cost pose and the last frame it came from are then in the
// old world frame: track() must estimate the initial pose again, or the motion model takes in the
// whole correction and the next frame's prediction is off by it. A local BA in between refines
// the map in place and keeps the low-cost pose (review, stop 25).
TEST(TrackerTest, AMapCorrectionAfterTheLowCostPoseIsFollowed) {
  auto map = std::make_shared<map::Map>();
  auto database = std::make_shared<vocabulary::BowDatabase>();
  Tracker tracker(testing::test_tracker_config(), testing::test_camera(), map,
                  testing::room_vocabulary(), database);
  const MappingStatus idle;
  const SE3 T_new_old(Mat3d(Eigen::AngleAxisd(0.05, Vec3d(0.3, 1.0, 0.2).normalized())),
                      Vec3d(0.08, -0.03, 0.05));
  constexpr std::size_t kCorrectedAt = 12;
  constexpr std::size_t kRefinedAt = 8;
  for (std::size_t k = 0; k < kCorrectedAt + 4; ++k) {
    Frame frame = tracker.prepare_frame(room_sequence().frames[k], cv::Mat());
    if (k > 0) {
      ASSERT_TRUE(tracker.low_cost_pose(frame)) << "frame " << k;
    }
    if (k == kRefinedAt) {
      // A local BA's write-back: points moved by a millimetre, in the same world frame.
      map->apply_update([&] {
        for (const map::MapPointPtr& p : map->map_points()) {
          p->set_position_w(p->position_w() + Vec3d(0.001, -0.001, 0.0005));
        }
      });
    }
    if (k == kCorrectedAt) {
      // A loop correction of the whole map, as loop closing writes it.
      map->apply_frame_change([&] {
        for (const map::KeyFramePtr& kf : map->keyframes()) {
          kf->set_T_c_w(kf->T_c_w() * T_new_old.inverse());
        }
        for (const map::MapPointPtr& p : map->map_points()) {
          p->set_position_w(T_new_old * p->position_w());
        }
      });
      map->notify_big_change();
    }
    const TrackingResult r = tracker.track(std::move(frame), idle);
    ASSERT_TRUE(r.tracked()) << "frame " << k;
    if (r.new_keyframe) associate_keyframe(r.new_keyframe, *database);
    const SE3 truth = k >= kCorrectedAt ? T_new_old * truth_in_map(k) : truth_in_map(k);
    EXPECT_LT(pose_error(*r.T_w_c, truth).translation_m, 0.01) << "frame " << k;
    if (k > kCorrectedAt) {
      EXPECT_EQ(r.method, TrackingMethod::kMotionModel)
          << "frame " << k << ": the motion model was off by the correction";
    }
  }
  EXPECT_EQ(tracker.low_cost_poses_redone(), 1u) << "only the loop correction discards it";
}

TEST(TrackerTest, SplitStepsMustBeCalledOnThePreparedFrame) {
  auto map = std::make_shared<map::Map>();
  Tracker tracker(testing::test_tracker_config(), testing::test_camera(), map,
                  testing::room_vocabulary(), nullptr);
  Frame first = tracker.prepare_frame(room_sequence().frames[0], cv::Mat());
  Frame second = tracker.prepare_frame(room_sequence().frames[1], cv::Mat());
  EXPECT_THROW(tracker.track(std::move(first), MappingStatus{}), Error);
  EXPECT_FALSE(tracker.low_cost_pose(second));  // not initialized yet
  EXPECT_TRUE(tracker.track(std::move(second), MappingStatus{}).tracked());
}

io::RgbdFrame blank_frame(std::size_t index, double stamp) {
  io::RgbdFrame f;
  f.index = index;
  f.timestamp_s = stamp;
  f.rgb = cv::Mat(480, 640, CV_8UC3, cv::Scalar(0, 0, 0));
  f.depth_m = cv::Mat(480, 640, CV_32F, cv::Scalar(0.0f));
  return f;
}

// Only keypoints with depth become map points, so a frame whose depth is missing (a dropout, the
// sensor covered) does not start the map: it would start an empty one that the next frame cannot
// track. The first frame with depth does.
TEST(TrackerTest, AFrameWithoutDepthDoesNotStartTheMap) {
  auto map = std::make_shared<map::Map>();
  Tracker tracker(testing::test_tracker_config(), testing::test_camera(), map,
                  testing::room_vocabulary(), nullptr);
  io::RgbdFrame no_depth = room_sequence().frames[0];
  no_depth.depth_m = cv::Mat(no_depth.depth_m.size(), CV_32F, cv::Scalar(0.0f));
  const TrackingResult first = tracker.track(tracker.prepare_frame(no_depth, cv::Mat()), {});
  ASSERT_GT(first.num_features, 500u) << "the frame has keypoints, only no depth";
  EXPECT_FALSE(first.tracked());
  EXPECT_EQ(tracker.state(), TrackingState::kNotInitialized);
  EXPECT_EQ(map->keyframe_count(), 0u);
  const TrackingResult second =
      tracker.track(tracker.prepare_frame(room_sequence().frames[1], cv::Mat()), {});
  EXPECT_TRUE(second.tracked());
  EXPECT_EQ(second.method, TrackingMethod::kInitialization);
  EXPECT_GT(map->map_point_count(), 100u);
}

TEST(TrackerTest, RelocalizesAfterBlankFrames) {
  auto map = std::make_shared<map::Map>();
  auto database = std::make_shared<vocabulary::BowDatabase>();
  TrackerConfig config = testing::test_tracker_config();
  // The short sequence makes only a few keyframes; ORB-SLAM2 would reset such a map when lost.
  config.reset_when_lost_max_keyframes = -1;
  Tracker tracker(config, testing::test_camera(), map, testing::room_vocabulary(), database);
  const MappingStatus idle;
  const auto& seq = room_sequence();
  const std::size_t tracked = 30;
  for (std::size_t k = 0; k < tracked; ++k) {
    const TrackingResult r = tracker.track(seq.frames[k], cv::Mat(), idle);
    ASSERT_TRUE(r.tracked()) << "frame " << k;
    if (r.new_keyframe) associate_keyframe(r.new_keyframe, *database);
  }
  ASSERT_GE(map->keyframe_count(), 2u);

  double stamp = seq.frames[tracked - 1].timestamp_s;
  for (std::size_t k = 0; k < 3; ++k) {
    const TrackingResult r =
        tracker.track(blank_frame(tracked + k, stamp += 1.0 / 30), cv::Mat(), idle);
    EXPECT_EQ(r.state, TrackingState::kLost);
    EXPECT_FALSE(r.T_w_c.has_value());
    EXPECT_FALSE(r.map_reset);
  }
  // Back at a place seen before (near frame 12), but from a slightly different pose.
  const SE3 T_w_c = seq.T_w_c[12] * SE3(so3_exp(Vec3d(0.0, 0.01, 0.0)), Vec3d(0.02, 0.0, 0.0));
  const io::RgbdFrame revisit =
      testing::room().render(testing::test_camera(), T_w_c, tracked + 3, stamp + 1.0 / 30, 1.0);
  const TrackingResult r = tracker.track(revisit, cv::Mat(), idle);
  ASSERT_EQ(r.state, TrackingState::kRelocalized);
  EXPECT_EQ(r.method, TrackingMethod::kRelocalization);
  ASSERT_TRUE(r.T_w_c.has_value());
  const testing::PoseError e = pose_error(*r.T_w_c, seq.T_w_c[0].inverse() * T_w_c);
  EXPECT_LT(e.translation_m, 0.01);
  EXPECT_LT(e.rotation_deg, 0.5);
  EXPECT_GE(r.num_inliers, 50);

  // Tracking goes on normally from there.
  const SE3 T_w_c_next = T_w_c * SE3(so3_exp(Vec3d(0.0, 0.005, 0.0)), Vec3d(0.01, 0.0, 0.0));
  const TrackingResult next =
      tracker.track(testing::room().render(testing::test_camera(), T_w_c_next, tracked + 4,
                                           stamp + 2.0 / 30, 1.0),
                    cv::Mat(), idle);
  ASSERT_EQ(next.state, TrackingState::kOk);
  EXPECT_LT(pose_error(*next.T_w_c, seq.T_w_c[0].inverse() * T_w_c_next).translation_m, 0.01);
  // Lost frames are left out of the trajectory.
  EXPECT_EQ(tracker.camera_trajectory().size(), tracked + 2);
}

// The camera pans 87 degrees and jumps back to where it started (a gap in the frames, the view
// swept back): the motion model predicts further panning and the reference keyframe, made near
// the end of the pan, shares too little of the view, so tracking fails. Relocalization finds the
// first keyframes in that same frame; ORB-SLAM2 (same_frame: false) loses the frame and
// relocalizes the next one. The dynamic pipeline's way in (prepare_frame, a low_cost_pose() that
// fails, track) does the same.
TEST(TrackerTest, AFrameWhoseTrackingFailsIsRelocalizedAtOnce) {
  const camera::PinholeCamera camera = testing::test_camera();
  const auto pan = [](double yaw_deg) {
    return SE3(so3_exp(Vec3d(0.0, yaw_deg * M_PI / 180.0, 0.0)), Vec3d(0.0, 0.0, 0.0));
  };
  const std::size_t panned = 30;  // frames 0..29 at 0, 3, ..., 87 degrees
  const SE3 T_w_c_jump = pan(3.0) * SE3(Mat3d::Identity(), Vec3d(0.02, 0.0, 0.0));
  const SE3 T_w_c_next = pan(4.0) * SE3(Mat3d::Identity(), Vec3d(0.02, 0.0, 0.0));
  const MappingStatus idle;
  struct Case {
    bool same_frame;
    bool low_cost_pose;
  };
  for (const Case c : {Case{false, false}, Case{true, false}, Case{true, true}}) {
    SCOPED_TRACE(std::string("same_frame: ") + (c.same_frame ? "true" : "false") +
                 (c.low_cost_pose ? ", through low_cost_pose()" : ""));
    TrackerConfig config = testing::test_tracker_config();
    config.relocalization.same_frame = c.same_frame;
    config.reset_when_lost_max_keyframes = -1;  // a lost frame must not reset the small map
    auto map = std::make_shared<map::Map>();
    auto database = std::make_shared<vocabulary::BowDatabase>();
    Tracker tracker(config, camera, map, testing::room_vocabulary(), database);
    double stamp = 1000.0;
    bool all_tracked = true;
    for (std::size_t k = 0; k < panned; ++k, stamp += 1.0 / 30) {
      const TrackingResult r = tracker.track(
          testing::room().render(camera, pan(3.0 * k), k, stamp, 1.0), cv::Mat(), idle);
      all_tracked = all_tracked && r.tracked() && !r.relocalized_at_once;
      if (r.new_keyframe) associate_keyframe(r.new_keyframe, *database);
    }
    ASSERT_TRUE(all_tracked) << "the pan is tracked frame by frame";
    const io::RgbdFrame jump_frame = testing::room().render(camera, T_w_c_jump, panned, stamp, 1.0);
    TrackingResult jump;
    if (c.low_cost_pose) {
      Frame prepared = tracker.prepare_frame(jump_frame, cv::Mat());
      EXPECT_FALSE(tracker.low_cost_pose(prepared).has_value());
      jump = tracker.track(std::move(prepared), idle);
    } else {
      jump = tracker.track(jump_frame, cv::Mat(), idle);
    }
    const TrackingResult next =
        tracker.track(testing::room().render(camera, T_w_c_next, panned + 1, stamp + 1.0 / 30, 1.0),
                      cv::Mat(), idle);
    if (!c.same_frame) {
      EXPECT_EQ(jump.state, TrackingState::kLost);
      EXPECT_FALSE(jump.relocalized_at_once);
      EXPECT_EQ(next.state, TrackingState::kRelocalized);
      EXPECT_FALSE(next.relocalized_at_once) << "relocalized after being lost";
      EXPECT_EQ(tracker.camera_trajectory().size(), panned + 1);
    } else {
      EXPECT_EQ(jump.state, TrackingState::kRelocalized);
      EXPECT_TRUE(jump.relocalized_at_once);
      EXPECT_EQ(jump.method, TrackingMethod::kRelocalization);
      EXPECT_GT(jump.timings.initial_pose_ms, 0.0);
      EXPECT_GT(jump.timings.local_map_ms, 0.0);
      EXPECT_GE(jump.num_inliers, 50);
      if (jump.T_w_c) {
        const testing::PoseError e = pose_error(*jump.T_w_c, T_w_c_jump);
        EXPECT_LT(e.translation_m, 0.01);
        EXPECT_LT(e.rotation_deg, 0.5);
      } else {
        ADD_FAILURE() << "the jump frame has no pose";
      }
      // No motion model right after a relocalization (ORB-SLAM2): the reference keyframe.
      EXPECT_EQ(next.state, TrackingState::kOk);
      EXPECT_EQ(next.method, TrackingMethod::kReferenceKeyFrame);
      EXPECT_EQ(tracker.camera_trajectory().size(), panned + 2);
    }
    if (next.T_w_c) {
      EXPECT_LT(pose_error(*next.T_w_c, T_w_c_next).translation_m, 0.01);
    } else {
      ADD_FAILURE() << "the frame after the jump has no pose";
    }
  }
}

TEST(TrackerTest, ResetsWhenLostWithATinyMap) {
  auto map = std::make_shared<map::Map>();
  auto database = std::make_shared<vocabulary::BowDatabase>();
  Tracker tracker(testing::test_tracker_config(), testing::test_camera(), map,
                  testing::room_vocabulary(), database);
  const MappingStatus idle;
  const auto& seq = room_sequence();
  TrackingResult r = tracker.track(blank_frame(0, 1.0), cv::Mat(), idle);
  EXPECT_EQ(r.state, TrackingState::kNotInitialized);  // no features: no map
  r = tracker.track(seq.frames[0], cv::Mat(), idle);
  ASSERT_EQ(r.state, TrackingState::kOk);
  ASSERT_TRUE(r.new_keyframe);
  associate_keyframe(r.new_keyframe, *database);
  EXPECT_EQ(map->keyframe_count(), 1u);
  EXPECT_GT(map->map_point_count(), 500u);

  r = tracker.track(blank_frame(2, 2.0), cv::Mat(), idle);
  EXPECT_EQ(r.state, TrackingState::kLost);
  EXPECT_TRUE(r.map_reset);
  EXPECT_EQ(map->keyframe_count(), 0u);
  EXPECT_EQ(map->map_point_count(), 0u);
  EXPECT_EQ(database->size(), 0u);
  EXPECT_EQ(tracker.state(), TrackingState::kNotInitialized);

  r = tracker.track(seq.frames[1], cv::Mat(), idle);
  EXPECT_EQ(r.state, TrackingState::kOk);
  EXPECT_EQ(r.method, TrackingMethod::kInitialization);
  EXPECT_EQ(tracker.camera_trajectory().size(), 1u);
}

TEST(TrackerTest, DynamicMaskKeepsTrackingOnTheRest) {
  // A static "object" masked out in every frame: tracking uses the rest of the image.
  auto map = std::make_shared<map::Map>();
  auto database = std::make_shared<vocabulary::BowDatabase>();
  Tracker tracker(testing::test_tracker_config(), testing::test_camera(), map,
                  testing::room_vocabulary(), database);
  cv::Mat mask(480, 640, CV_8U, cv::Scalar(0));
  mask(cv::Rect(240, 120, 200, 260)).setTo(255);
  const MappingStatus idle;
  for (std::size_t k = 0; k < 10; ++k) {
    const TrackingResult r = tracker.track(room_sequence().frames[k], mask, idle);
    ASSERT_TRUE(r.tracked()) << "frame " << k;
    if (r.new_keyframe) associate_keyframe(r.new_keyframe, *database);
    EXPECT_LT(pose_error(*r.T_w_c, truth_in_map(k)).translation_m, 0.01);
  }
  for (const cv::KeyPoint& kp : tracker.last_frame().features().keypoints) {
    EXPECT_EQ(mask.at<std::uint8_t>(cv::Point(static_cast<int>(std::lround(kp.pt.x)),
                                              static_cast<int>(std::lround(kp.pt.y)))),
              0);
  }
}

TEST(TrackerTest, RefusesAVocabularyOfAnotherDescriptorPattern) {
  auto other = std::make_shared<vocabulary::Vocabulary>(*testing::room_vocabulary());
  other->set_descriptor_tag(0x0123456789abcdefull);
  auto map = std::make_shared<map::Map>();
  try {
    Tracker tracker(testing::test_tracker_config(), testing::test_camera(), map, other, nullptr);
    FAIL() << "expected ddl::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("another ORB descriptor"), std::string::npos) << e.what();
  }
  // An untagged vocabulary (tag 0: not recorded) and the matching tag are accepted.
  other->set_descriptor_tag(0);
  EXPECT_NO_THROW(
      Tracker(testing::test_tracker_config(), testing::test_camera(), map, other, nullptr));
}

// An idf vocabulary trained on one image weighs every word 0, so every bag of words is empty and
// relocalization and loop detection find nothing without a word said (review, stop 26).
TEST(TrackerTest, RefusesAVocabularyWhoseWordsAllWeighZero) {
  const vocabulary::Vocabulary& room = *testing::room_vocabulary();
  std::vector<vocabulary::VocabularyNode> nodes = room.nodes();
  for (vocabulary::VocabularyNode& node : nodes) node.weight = 0.0f;
  auto unweighted = std::make_shared<vocabulary::Vocabulary>(
      vocabulary::Vocabulary::from_nodes(room.branching(), room.levels(), room.weighting(), nodes));
  unweighted->set_descriptor_tag(room.descriptor_tag());
  auto map = std::make_shared<map::Map>();
  try {
    Tracker tracker(testing::test_tracker_config(), testing::test_camera(), map, unweighted,
                    nullptr);
    FAIL() << "expected ddl::Error";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("weighs 0"), std::string::npos) << e.what();
  }
  // One word with a weight is enough.
  nodes[room.node_of_word(0)].weight = 1.0f;
  auto one = std::make_shared<vocabulary::Vocabulary>(
      vocabulary::Vocabulary::from_nodes(room.branching(), room.levels(), room.weighting(), nodes));
  one->set_descriptor_tag(room.descriptor_tag());
  EXPECT_NO_THROW(
      Tracker(testing::test_tracker_config(), testing::test_camera(), map, one, nullptr));
}

}  // namespace
}  // namespace ddl::tracking
