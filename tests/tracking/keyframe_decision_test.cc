#include "ddl/tracking/keyframe_decision.h"

#include <gtest/gtest.h>

#include "ddl/tracking/motion_model.h"

namespace ddl::tracking {
namespace {

KeyFrameContext healthy_context() {
  KeyFrameContext c;
  c.frame_id = 100;
  c.last_keyframe_frame_id = 95;
  c.last_relocalization_frame_id = 0;
  c.keyframes_in_map = 10;
  c.reference_tracked_points = 400;
  c.inliers = 380;  // 95% of the reference: tracking is strong
  c.close = {300, 20, 300};
  return c;
}

TEST(KeyFrameDecisionTest, NoKeyframeWhileTrackingIsStrong) {
  EXPECT_FALSE(need_new_keyframe(KeyFrameConfig{}, healthy_context()));
}

TEST(KeyFrameDecisionTest, InsertsWhenInliersDropBelowReferenceRatioAndMappingIdle) {
  KeyFrameContext c = healthy_context();
  c.inliers = 290;  // < 0.75 * 400
  EXPECT_TRUE(need_new_keyframe(KeyFrameConfig{}, c));
  c.mapping.accepts_keyframes = false;  // busy mapper, not long enough since the last keyframe
  c.mapping.queued_keyframes = 0;
  EXPECT_FALSE(need_new_keyframe(KeyFrameConfig{}, c));
  c.frame_id = c.last_keyframe_frame_id + 30;  // max_frames passed: queue it
  EXPECT_TRUE(need_new_keyframe(KeyFrameConfig{}, c));
  c.mapping.queued_keyframes = 3;  // queue full
  EXPECT_FALSE(need_new_keyframe(KeyFrameConfig{}, c));
  c.mapping.queued_keyframes = 0;
  c.mapping.stopped = true;
  EXPECT_FALSE(need_new_keyframe(KeyFrameConfig{}, c));
}

TEST(KeyFrameDecisionTest, CloseDepthCriterion) {
  KeyFrameContext c = healthy_context();
  c.close = {99, 71, 99};  // few tracked close points, many untracked ones
  EXPECT_TRUE(need_new_keyframe(KeyFrameConfig{}, c));
  c.close = {100, 71, 100};
  EXPECT_FALSE(need_new_keyframe(KeyFrameConfig{}, c));
  c.close = {99, 70, 99};
  EXPECT_FALSE(need_new_keyframe(KeyFrameConfig{}, c));
}

TEST(KeyFrameDecisionTest, FreshPointsOfTheLastKeyframeDoNotCountAsTrackedClose) {
  // Exploration: the frame tracks 450 close points, but only 80 of them were seen by more than
  // the last keyframe, which created the rest from depth.
  KeyFrameContext c = healthy_context();
  c.reference_tracked_points = 100;  // the last keyframe's points of >= 2 keyframes
  c.inliers = 460;
  c.close = {450, 500, 80};
  EXPECT_TRUE(need_new_keyframe(KeyFrameConfig{}, c));
  KeyFrameConfig orb_slam2;
  orb_slam2.close_needs_two_keyframes = false;  // ORB-SLAM2 counts all 450: no keyframe
  EXPECT_FALSE(need_new_keyframe(orb_slam2, c));
  c.close.tracked_established = 100;
  EXPECT_FALSE(need_new_keyframe(KeyFrameConfig{}, c));
}

TEST(KeyFrameDecisionTest, WeakTrackingQueuesEvenWhenBusy) {
  KeyFrameContext c = healthy_context();
  c.mapping.accepts_keyframes = false;
  c.inliers = 90;  // < 0.25 * 400
  EXPECT_TRUE(need_new_keyframe(KeyFrameConfig{}, c));
  c.inliers = 15;  // never with <= 15 inliers
  EXPECT_FALSE(need_new_keyframe(KeyFrameConfig{}, c));
}

TEST(KeyFrameDecisionTest, SingleKeyframeMapUsesLowerRatioAndFewerObservations) {
  KeyFrameContext c = healthy_context();
  c.keyframes_in_map = 1;
  c.inliers = 200;  // 50%: above the 40% threshold of a one-keyframe map
  EXPECT_FALSE(need_new_keyframe(KeyFrameConfig{}, c));
  c.inliers = 150;
  EXPECT_TRUE(need_new_keyframe(KeyFrameConfig{}, c));
  EXPECT_EQ(min_observations_for(1), 2);
  EXPECT_EQ(min_observations_for(2), 2);
  EXPECT_EQ(min_observations_for(3), 3);
}

TEST(KeyFrameDecisionTest, NoKeyframeRightAfterRelocalizationInABigMap) {
  KeyFrameContext c = healthy_context();
  c.inliers = 100;
  c.keyframes_in_map = 40;
  c.last_relocalization_frame_id = 96;  // 4 frames ago
  const KeyFrameConfig config;
  ASSERT_EQ(config.frames_after_relocalization, 5);
  EXPECT_FALSE(need_new_keyframe(config, c));
  c.keyframes_in_map = 30;  // small map: allowed
  EXPECT_TRUE(need_new_keyframe(config, c));
  c.keyframes_in_map = 40;
  c.last_relocalization_frame_id = 95;  // 5 frames ago: the map may grow again
  EXPECT_TRUE(need_new_keyframe(config, c));
  // ORB-SLAM2 holds the map for max_frames (30) frames.
  KeyFrameConfig orb_slam2;
  orb_slam2.frames_after_relocalization = orb_slam2.max_frames;
  c.last_relocalization_frame_id = 75;
  EXPECT_FALSE(need_new_keyframe(orb_slam2, c));
  c.last_relocalization_frame_id = 70;
  EXPECT_TRUE(need_new_keyframe(orb_slam2, c));
}

TEST(MotionModelTest, RepeatsTheLastRelativeMotion) {
  const SE3 T0(so3_exp(Vec3d(0.01, -0.02, 0.03)), Vec3d(0.1, 0.2, 0.3));
  const SE3 step(so3_exp(Vec3d(0.0, 0.02, 0.0)), Vec3d(0.01, 0.0, -0.02));
  const SE3 T1 = step * T0;
  MotionModel model;
  EXPECT_FALSE(model.valid());
  model.update(T1, T0, 0.033);
  ASSERT_TRUE(model.valid());
  EXPECT_EQ(model.interval_s(), 0.033);
  const SE3 predicted = model.predict(T1);
  const SE3 expected = step * T1;
  EXPECT_LT((predicted.matrix() - expected.matrix()).norm(), 1e-12);
  // Jitter within the gap ratio repeats V as it is (ORB-SLAM2); a gap scales it to the time.
  EXPECT_EQ(model.predict(T1, 0.040).matrix(), predicted.matrix());
  EXPECT_EQ(model.gap_ratio(0.040), 1.0);
  const SE3 three_steps = step * step * step * T1;
  EXPECT_LT((model.predict(T1, 0.099).matrix() - three_steps.matrix()).norm(), 1e-9);
  model.update(three_steps, T1, 0.099);  // learnt across the gap, predicted over one interval
  EXPECT_LT((model.predict(three_steps, 0.033).matrix() - (step * three_steps).matrix()).norm(),
            1e-9);
  model.reset();
  EXPECT_FALSE(model.valid());
}

TEST(MotionModelTest, AroundAGlitchedStampTheVelocityRepeatsOncePerFrame) {
  const SE3 step(so3_exp(Vec3d(0.0, 0.02, 0.0)), Vec3d(0.01, 0.0, -0.02));
  const auto expect_one_step = [&](const SE3& predicted, const SE3& from) {
    EXPECT_LT((predicted.matrix() - (step * from).matrix()).norm(), 1e-12);
  };
  SE3 T;
  MotionModel model;
  // A 30 Hz camera that drops a frame now and then: a 33 ms interval is no glitch even while
  // the third-smallest interval is 66 ms, and the base settles at 33 ms.
  for (const double interval : {0.033, 0.066, 0.066, 0.033, 0.066}) {
    model.update(step * T, T, interval);
    T = step * T;
  }
  EXPECT_EQ(model.base_interval_s(), 0.066);
  model.update(step * T, T, 0.033);
  T = step * T;
  EXPECT_EQ(model.interval_s(), 0.033);
  EXPECT_EQ(model.base_interval_s(), 0.033);
  // Frame k is stamped 1 ms after frame k-1, but the camera moved one interval's step: its
  // prediction is one step, not 3% of one.
  expect_one_step(model.predict(T, 0.001), T);
  EXPECT_NEAR(model.prior(T, 0.001, MotionPriorConfig{}).sqrt_information(0, 0), 200.0, 1e-9);
  const SE3 T_k = step * T;
  model.update(T_k, T, 0.001);
  EXPECT_EQ(model.interval_s(), 0.0) << "learnt over a glitch: of unknown interval";
  // Frame k+1 comes 65 ms after the glitched stamp: one step, not 65 (nor 2).
  expect_one_step(model.predict(T_k, 0.065), T_k);
  const SE3 T_k1 = step * T_k;
  model.update(T_k1, T_k, 0.065);
  EXPECT_EQ(model.interval_s(), 0.0) << "measured from the glitched stamp: unknown too";
  expect_one_step(model.predict(T_k1, 0.033), T_k1);  // not half a step
  model.update(step * T_k1, T_k1, 0.033);
  EXPECT_EQ(model.interval_s(), 0.033);
  EXPECT_EQ(model.base_interval_s(), 0.033) << "neither interval entered the history";

  // Glitches on every second frame: the base does not follow them.
  for (int k = 0; k < 20; ++k) {
    model.update(step * T, T, k % 2 == 0 ? 0.001 : 0.065);
    EXPECT_EQ(model.interval_s(), 0.0) << "update " << k;
  }
  EXPECT_EQ(model.base_interval_s(), 0.033);
  // reset() keeps the camera's rate; a camera that turns twice as fast is no glitch.
  model.reset();
  EXPECT_EQ(model.base_interval_s(), 0.033);
  model.update(step * T, T, 0.0167);
  EXPECT_EQ(model.interval_s(), 0.0167);

  // Without enough history a short interval cannot be judged, and it is kept.
  MotionModel fresh;
  for (int k = 0; k < 4; ++k) fresh.update(step * T, T, 0.033);
  fresh.update(T_k, T, 0.001);
  EXPECT_EQ(fresh.interval_s(), 0.001);
}

TEST(MotionModelTest, PriorWidensAcrossAGap) {
  MotionModel model;
  model.update(SE3(), SE3(), 0.033);
  MotionPriorConfig config;
  config.sigma_translation_m = 0.005;
  config.sigma_rotation_deg = 1.0;
  const SE3 predicted(so3_exp(Vec3d(0.1, 0.0, 0.0)), Vec3d(0.0, 0.2, 0.0));
  const optimization::PosePrior regular = model.prior(predicted, 0.036, config);  // jitter
  EXPECT_EQ(regular.T_c_w.matrix(), predicted.matrix());
  EXPECT_NEAR(regular.sqrt_information(0, 0), 200.0, 1e-9);
  EXPECT_NEAR(regular.sqrt_information(5, 5), 180.0 / M_PI, 1e-9);
  EXPECT_EQ(regular.sqrt_information(0, 1), 0.0);
  // Seven intervals later: sigma x 7 (1 + 7) / 2 = 28.
  const optimization::PosePrior gap = model.prior(predicted, 7 * 0.033, config);
  EXPECT_NEAR(gap.sqrt_information(1, 1), 200.0 / 28.0, 1e-9);
  EXPECT_NEAR(gap.sqrt_information(3, 3), 180.0 / M_PI / 28.0, 1e-9);
  // Learnt across that gap, predicted over one interval: sigma x 1 (7 + 1) / 2 = 4.
  model.update(SE3(), SE3(), 7 * 0.033);
  EXPECT_NEAR(model.prior(predicted, 0.033, config).sqrt_information(2, 2), 200.0 / 4.0, 1e-9);
}

}  // namespace
}  // namespace ddl::tracking
