#include "ddl/tracking/trajectory_recorder.h"

#include <gtest/gtest.h>

#include "ddl/map/map.h"

namespace ddl::tracking {
namespace {

std::shared_ptr<map::FrameFeatures> empty_features() {
  return std::make_shared<map::FrameFeatures>();
}

TEST(TrajectoryRecorderTest, FramesFollowTheirReferenceKeyframeAndCulledParents) {
  map::Map map;
  const SE3 T0_c_w;  // first keyframe at the origin
  const SE3 T1_c_w(so3_exp(Vec3d(0.0, 0.1, 0.0)), Vec3d(-0.2, 0.0, 0.0));
  auto kf0 = std::make_shared<map::KeyFrame>(map.next_keyframe_id(), 0.0, empty_features(), T0_c_w);
  auto kf1 = std::make_shared<map::KeyFrame>(map.next_keyframe_id(), 1.0, empty_features(), T1_c_w);
  kf1->set_parent(kf0);
  map.add_keyframe(kf0);
  map.add_keyframe(kf1);

  TrajectoryRecorder recorder;
  const SE3 frame_T_c_w(so3_exp(Vec3d(0.02, 0.12, 0.0)), Vec3d(-0.25, 0.01, 0.0));
  recorder.add_tracked(2.0, frame_T_c_w, kf1);
  recorder.add_lost(3.0);
  EXPECT_EQ(recorder.frames(), 2u);
  EXPECT_EQ(recorder.tracked_frames(), 1u);
  io::Trajectory t = recorder.camera_trajectory();
  ASSERT_EQ(t.size(), 1u);
  EXPECT_LT((t[0].T_w_c().matrix() - frame_T_c_w.inverse().matrix()).norm(), 1e-9);

  // A correction moves keyframe 1: the frame moves with it.
  const SE3 correction(so3_exp(Vec3d(0.0, 0.0, 0.05)), Vec3d(0.1, 0.0, 0.0));  // T_w_new_w_old
  kf1->set_T_c_w(T1_c_w * correction.inverse());
  t = recorder.camera_trajectory();
  EXPECT_LT((t[0].T_w_c().matrix() - (correction * frame_T_c_w.inverse()).matrix()).norm(), 1e-9);

  // Keyframe 1 is culled, then its parent moves: the frame follows through T_c_parent.
  ASSERT_TRUE(kf1->set_bad());
  const SE3 second(so3_exp(Vec3d(0.03, 0.0, 0.0)), Vec3d(0.0, 0.2, 0.0));
  kf0->set_T_c_w(T0_c_w * second.inverse());
  t = recorder.camera_trajectory();
  ASSERT_EQ(t.size(), 1u);
  EXPECT_LT((t[0].T_w_c().matrix() - (second * correction * frame_T_c_w.inverse()).matrix()).norm(),
            1e-9);
}

}  // namespace
}  // namespace ddl::tracking
