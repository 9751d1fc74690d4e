// Camera motions: TUM-like speeds, smoothness, staying inside the room, closing the loop.

#include "ddl/synthetic/motion.h"

#include <gtest/gtest.h>

#include <cmath>

#include "ddl/synthetic/people.h"
#include "ddl/synthetic/sequence.h"

namespace ddl::synthetic {
namespace {

struct Speeds {
  double mean_mps = 0;
  double mean_degps = 0;
  double max_mps = 0;
  double max_jump_ratio = 0;  // largest change of velocity between steps / mean speed change
};

Speeds measure(const MotionConfig& config, double duration_s) {
  constexpr double dt = 1.0 / 30.0;
  Speeds s;
  int n = 0;
  for (double t = 0; t + dt <= duration_s; t += dt, ++n) {
    const SE3 a = camera_pose(config, t);
    const SE3 b = camera_pose(config, t + dt);
    const double v = (b.translation() - a.translation()).norm() / dt;
    s.mean_mps += v;
    s.max_mps = std::max(s.max_mps, v);
    s.mean_degps += (a.inverse() * b).rotation_angle() * 180 / M_PI / dt;
  }
  s.mean_mps /= n;
  s.mean_degps /= n;
  return s;
}

TEST(Motion, SpeedsAreTumLike) {
  MotionConfig config;
  config.type = MotionType::kXyz;
  Speeds s = measure(config, 30);
  EXPECT_GT(s.mean_mps, 0.15);
  EXPECT_LT(s.mean_mps, 0.45);
  EXPECT_LT(s.mean_degps, 3.0);
  config.type = MotionType::kRpy;
  s = measure(config, 30);
  EXPECT_GT(s.mean_degps, 15.0);
  EXPECT_LT(s.mean_degps, 45.0);
  EXPECT_LT(s.mean_mps, 0.1);
  config.type = MotionType::kHalfsphere;
  s = measure(config, 30);
  EXPECT_GT(s.mean_mps, 0.15);
  EXPECT_LT(s.mean_mps, 0.45);
  EXPECT_GT(s.mean_degps, 12.0);
  EXPECT_LT(s.mean_degps, 45.0);
  config.type = MotionType::kStatic;
  s = measure(config, 30);
  EXPECT_LT(s.max_mps, 0.06);
  EXPECT_LT(s.mean_degps, 3.0);
  config.type = MotionType::kLoop;
  config.loop_period_s = 30;
  s = measure(config, 30);
  EXPECT_GT(s.mean_mps, 0.15);
  EXPECT_LT(s.mean_mps, 0.45);
}

TEST(Motion, IsSmooth) {
  // C2: the second difference of position over one frame stays tiny (no jumps or kinks).
  for (auto type : {MotionType::kXyz, MotionType::kRpy, MotionType::kHalfsphere,
                    MotionType::kStatic, MotionType::kLoop}) {
    MotionConfig config;
    config.type = type;
    constexpr double dt = 1.0 / 30.0;
    double max_accel = 0;
    for (double t = dt; t < 20; t += dt) {
      const Vec3d a = camera_pose(config, t - dt).translation();
      const Vec3d b = camera_pose(config, t).translation();
      const Vec3d c = camera_pose(config, t + dt).translation();
      max_accel = std::max(max_accel, (a - 2 * b + c).norm() / (dt * dt));
    }
    EXPECT_LT(max_accel, 3.0) << to_string(type) << " (m/s^2)";
  }
}

TEST(Motion, CamerasStayInsideTheRoomAwayFromWalls) {
  for (const auto& preset : presets()) {
    if (!preset.background_in_shared.empty()) continue;
    MotionConfig config;
    config.type = preset.config.motion;
    config.seed = preset.config.seed;
    config.loop_period_s = (preset.config.frames - 1) / 30.0 / preset.config.loop_turns;
    for (int i = 0; i < preset.config.frames; i += 5) {
      const Vec3d p = camera_pose(config, i / 30.0).translation();
      EXPECT_GT(p.x(), 0.6) << preset.name;
      EXPECT_LT(p.x(), 5.4) << preset.name;
      EXPECT_GT(p.y(), 0.6) << preset.name;
      EXPECT_LT(p.y(), 4.4) << preset.name;
      EXPECT_GT(p.z(), 0.9) << preset.name;
      EXPECT_LT(p.z(), 2.2) << preset.name;
    }
  }
}

TEST(Motion, LoopReturnsToItsStart) {
  MotionConfig config;
  config.type = MotionType::kLoop;
  config.loop_period_s = 899 / 30.0;
  const SE3 first = camera_pose(config, 0.0);
  const SE3 last = camera_pose(config, config.loop_period_s);
  EXPECT_LT((first.translation() - last.translation()).norm(), 1e-9);
  EXPECT_LT((first.inverse() * last).rotation_angle(), 1e-9);
  // Halfway it is far from the start.
  EXPECT_GT(
      (camera_pose(config, config.loop_period_s / 2).translation() - first.translation()).norm(),
      1.0);
}

TEST(Motion, ParseNamesTheKey) {
  EXPECT_EQ(parse_motion_type("rpy"), MotionType::kRpy);
  try {
    parse_motion_type("spiral", "preset.motion");
    FAIL() << "expected a ConfigError";
  } catch (const std::exception& e) {
    EXPECT_NE(std::string(e.what()).find("preset.motion"), std::string::npos);
  }
}

TEST(People, TracksMoveAtHumanSpeeds) {
  PersonTrack walker;
  walker.a_w = Vec3d(1.7, 2.1, 0);
  walker.b_w = Vec3d(4.3, 2.1, 0);
  walker.period_s = 8;
  double max_speed = 0;
  for (double t = 0; t < 16; t += 0.1) {
    const auto a = person_state(walker, t);
    const auto b = person_state(walker, t + 0.1);
    ASSERT_TRUE(a.visible);
    max_speed = std::max(max_speed, (b.foot_w - a.foot_w).norm() / 0.1);
  }
  EXPECT_GT(max_speed, 0.6);
  EXPECT_LT(max_speed, 1.6);
  PersonTrack late;
  late.type = PersonTrackType::kAppearing;
  late.a_w = Vec3d(0.7, 4.45, 0);
  late.b_w = Vec3d(2.9, 4.45, 0);
  late.appear_s = 10;
  EXPECT_FALSE(person_state(late, 9.9).visible);
  EXPECT_TRUE(person_state(late, 10.1).visible);
  EXPECT_NEAR(person_state(late, 20).foot_w.x(), 2.9, 0.1);
}

}  // namespace
}  // namespace ddl::synthetic
