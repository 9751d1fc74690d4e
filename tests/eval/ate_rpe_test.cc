// ATE and RPE on synthetic trajectories whose errors are known exactly.

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "ddl/core/error.h"
#include "ddl/core/se3.h"
#include "ddl/eval/ate.h"
#include "ddl/eval/rpe.h"

namespace ddl::eval {
namespace {

constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr double kDt = 1.0 / 32.0;  // exact in binary, so t + 1 s lands exactly on a frame
constexpr double kStart = 1000.0;

// A camera that moves and turns smoothly: every relative motion is different.
SE3 moving_pose(double t) {
  return SE3(so3_exp(Vec3d(0.3 * std::sin(t), 0.2 * t, 0.1 * std::cos(0.7 * t))),
             Vec3d(std::cos(t), 0.5 * std::sin(1.3 * t), 0.1 * t));
}

// A camera that only rotates about its centre (as in fr1_rpy).
SE3 turning_pose(double t) {
  return SE3(so3_exp(Vec3d(0.4 * std::sin(t), 0.3 * std::cos(0.5 * t), 0.25 * t)), Vec3d::Zero());
}

template <typename PoseFn>
io::Trajectory make_trajectory(PoseFn pose, int n) {
  io::Trajectory out;
  for (int k = 0; k < n; ++k) {
    const double t = k * kDt;
    out.emplace_back(kStart + t, pose(t));
  }
  return out;
}

TEST(RpeTest, TranslationalDriftPerSecondIsTheRpe) {
  // Estimate = world-frame drift of v metres per second applied to a general motion:
  // E = inv(gt_0) * exp(v) * gt_0 has translation R_0^T v, so |E.t| = |v| exactly, rotation 0.
  const Vec3d v(0.03, -0.02, 0.01);
  const int n = 320;  // 10 s
  const io::Trajectory gt = make_trajectory(moving_pose, n);
  const io::Trajectory est =
      make_trajectory([&](double t) { return SE3(Quatd::Identity(), t * v) * moving_pose(t); }, n);

  const RpeResult r = compute_rpe(gt, est);
  // Pairs (i, i + 32); the script drops the pair whose second pose is the last one, and every
  // later i (its closest index is the last one too).
  ASSERT_EQ(r.pairs.size(), static_cast<std::size_t>(n - 33));
  for (const RpePair& p : r.pairs) {
    ASSERT_EQ(p.stamp_est_1_s - p.stamp_est_0_s, 1.0);
    EXPECT_NEAR(p.trans_error_m, v.norm(), 1e-12);
    EXPECT_NEAR(p.rot_error_rad, 0.0, 2e-7);  // arccos near 1 amplifies rounding to ~1e-8
  }
  EXPECT_NEAR(r.trans_m.rmse, v.norm(), 1e-12);
  EXPECT_NEAR(r.trans_m.median, v.norm(), 1e-12);
  EXPECT_NEAR(r.trans_m.std, 0.0, 1e-12);
}

TEST(RpeTest, RotationalAndTranslationalIncrementPerSecondIsTheRpe) {
  // Camera turning in place; estimate = exp(t * xi) * gt(t). Then E = inv(gt_0) exp(xi) gt_0:
  // its angle is |phi| and its translation R_0^T * (translation of exp(xi)).
  Vec6d xi;
  xi << 0.02, 0.01, -0.015, 0.01, -0.03, 0.02;  // [rho; phi] per second
  const SE3 step = SE3::exp(xi);
  const int n = 256;
  const io::Trajectory gt = make_trajectory(turning_pose, n);
  const io::Trajectory est =
      make_trajectory([&](double t) { return SE3::exp(t * xi) * turning_pose(t); }, n);

  const RpeResult r = compute_rpe(gt, est);
  ASSERT_EQ(r.pairs.size(), static_cast<std::size_t>(n - 33));
  const double expected_rot_deg = xi.tail<3>().norm() * kRadToDeg;
  const double expected_trans = step.translation().norm();
  for (const RpePair& p : r.pairs) {
    EXPECT_NEAR(p.trans_error_m, expected_trans, 1e-12);
    EXPECT_NEAR(p.rot_error_rad * kRadToDeg, expected_rot_deg, 1e-9);
  }
  EXPECT_NEAR(r.rot_deg.rmse, expected_rot_deg, 1e-9);
  EXPECT_NEAR(r.rot_deg.mean, expected_rot_deg, 1e-9);
  EXPECT_NEAR(r.trans_m.mean, expected_trans, 1e-12);
}

TEST(RpeTest, FrameDeltaPairsNeighboursAndDropsTheLastPair) {
  const Vec3d v(0.0, 0.0, 0.064);  // 0.064 m/s = 0.002 m per frame at 32 Hz
  const int n = 50;
  const io::Trajectory gt = make_trajectory(moving_pose, n);
  const io::Trajectory est =
      make_trajectory([&](double t) { return SE3(Quatd::Identity(), t * v) * moving_pose(t); }, n);
  RpeOptions o;
  o.delta = 1.0;
  o.delta_unit = DeltaUnit::kFrames;
  const RpeResult r = compute_rpe(gt, est, o);
  ASSERT_EQ(r.pairs.size(), static_cast<std::size_t>(n - 2));  // (n-2, n-1) and (n-1, n-1) dropped
  EXPECT_EQ(r.pairs.front().stamp_est_1_s, kStart + kDt);
  EXPECT_NEAR(r.trans_m.rmse, 0.002, 1e-12);
}

TEST(RpeTest, DropsZeroQuaternionPosesAndSkipsPairsWithoutGroundTruth) {
  const int n = 200;
  const io::Trajectory gt_full = make_trajectory(moving_pose, n);
  io::Trajectory est = gt_full;
  est[10].q_xyzw.setZero();  // the script skips such lines in read_trajectory
  // Ground truth missing for 1 s in the middle: pairs touching that hole are skipped.
  io::Trajectory gt;
  for (const io::StampedPose& p : gt_full) {
    if (p.timestamp_s < kStart + 3.0 || p.timestamp_s > kStart + 4.0) gt.push_back(p);
  }
  const RpeResult r = compute_rpe(gt, est);
  EXPECT_EQ(r.est_poses_used, static_cast<std::size_t>(n - 1));
  EXPECT_EQ(r.est_zero_quaternions, 1u);
  EXPECT_DOUBLE_EQ(r.gt_max_time_difference_s, 2.0 * kDt);
  EXPECT_LT(r.pairs.size(), r.candidate_pairs);
  int off_stamp_pairs = 0;
  for (const RpePair& p : r.pairs) {
    EXPECT_NE(p.stamp_est_0_s, est[10].timestamp_s);
    EXPECT_LE(std::abs(p.stamp_gt_0_s - p.stamp_est_0_s), 2.0 * kDt);
    EXPECT_LE(std::abs(p.stamp_gt_1_s - p.stamp_est_1_s), 2.0 * kDt);
    if (p.stamp_gt_0_s == p.stamp_est_0_s && p.stamp_gt_1_s == p.stamp_est_1_s) {
      EXPECT_NEAR(p.trans_error_m, 0.0, 1e-12);
    } else {
      ++off_stamp_pairs;  // beside the hole: matched to ground truth up to 2 intervals away
      EXPECT_GT(p.trans_error_m, 0.0);
    }
  }
  EXPECT_GT(off_stamp_pairs, 0);
  // The ATE keeps the zero-quaternion pose (it uses positions only, as evaluate_ate.py).
  EXPECT_EQ(compute_ate(gt_full, est).est_poses, static_cast<std::size_t>(n));
}

TEST(RpeTest, FindClosestIndexFollowsTheScriptsSearch) {
  const std::vector<double> l{0.0, 1.0, 2.0, 3.0};
  EXPECT_EQ(find_closest_index(l, 1.0), 1u);
  EXPECT_EQ(find_closest_index(l, -5.0), 0u);
  EXPECT_EQ(find_closest_index(l, 7.0), 3u);
  EXPECT_EQ(find_closest_index(l, 2.2), 2u);
  // Equidistant from 1 and 2: the search visits 2 first and keeps it (a strict '<' later).
  EXPECT_EQ(find_closest_index(l, 1.5), 2u);
  // Equidistant from 0 and 1: index 0 is the initial best and is kept.
  EXPECT_EQ(find_closest_index(l, 0.5), 0u);
}

TEST(RpeTest, Transform44NormalisesTheQuaternionLikeTheScript) {
  io::StampedPose p;
  p.t_w_c = Vec3d(1, 2, 3);
  const Quatd q = Quatd(Eigen::AngleAxisd(0.8, Vec3d(1, -2, 0.5).normalized()));
  p.q_xyzw = 3.0 * Vec4d(q.x(), q.y(), q.z(), q.w());  // not unit length
  const Mat4d T = tum_transform44(p);
  EXPECT_LT((T.block<3, 3>(0, 0) - q.toRotationMatrix()).cwiseAbs().maxCoeff(), 1e-14);
  EXPECT_TRUE((T.block<3, 1>(0, 3) == p.t_w_c));
  EXPECT_TRUE((T.row(3) == Eigen::RowVector4d(0, 0, 0, 1)));
}

TEST(RpeTest, ScaleMultipliesTheEstimatesRelativeTranslation) {
  // Estimate is the ground truth at half size; scale 2 makes it exact.
  const int n = 100;
  const io::Trajectory gt = make_trajectory(moving_pose, n);
  const io::Trajectory est = make_trajectory(
      [](double t) {
        const SE3 p = moving_pose(t);
        return SE3(p.quaternion(), 0.5 * p.translation());
      },
      n);
  RpeOptions o;
  EXPECT_GT(compute_rpe(gt, est, o).trans_m.rmse, 0.1);
  o.scale = 2.0;
  EXPECT_NEAR(compute_rpe(gt, est, o).trans_m.rmse, 0.0, 1e-12);
}

TEST(AteTest, RigidlyMovedEstimateHasZeroErrorAndTheInverseAlignment) {
  const int n = 150;
  const io::Trajectory gt = make_trajectory(moving_pose, n);
  const SE3 T_est_gt(so3_exp(Vec3d(0.2, -0.4, 1.0)), Vec3d(3.0, -1.0, 0.5));
  io::Trajectory est;
  for (const io::StampedPose& p : gt) est.emplace_back(p.timestamp_s, T_est_gt * p.T_w_c());

  const AteResult r = compute_ate(gt, est);
  EXPECT_EQ(r.stats_m.count, static_cast<std::size_t>(n));
  EXPECT_LT(r.stats_m.max, 1e-9);
  const SE3 T_gt_est = T_est_gt.inverse();
  EXPECT_LT((r.alignment.R_gt_est - T_gt_est.rotation()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_LT((r.alignment.t_gt_est - T_gt_est.translation()).cwiseAbs().maxCoeff(), 1e-9);
  EXPECT_EQ(r.est_all_xyz_aligned.cols(), n);
}

TEST(AteTest, KnownErrorsGiveKnownStatistics) {
  // Estimate = ground truth with +d and -d offsets along z on a planar (z = 0) path that visits
  // every position twice (once with each sign). The offsets cancel in the alignment, which stays
  // the identity, so every error is exactly d.
  const double d = 0.05;
  io::Trajectory gt;
  io::Trajectory est;
  for (int k = 0; k < 64; ++k) {
    const double t = k * kDt;
    const double angle = 0.1 * (k / 2);
    const SE3 p(Quatd::Identity(), Vec3d(std::cos(angle), std::sin(angle), 0.0));
    gt.emplace_back(kStart + t, p);
    est.emplace_back(kStart + t,
                     SE3(Quatd::Identity(), p.translation() + Vec3d(0, 0, k % 2 == 0 ? d : -d)));
  }
  const AteResult r = compute_ate(gt, est);
  EXPECT_NEAR(r.stats_m.rmse, d, 1e-9);
  EXPECT_NEAR(r.stats_m.min, d, 1e-9);
  EXPECT_NEAR(r.stats_m.max, d, 1e-9);
  EXPECT_NEAR(r.stats_m.std, 0.0, 1e-9);
}

TEST(AteTest, AlignScaleRecoversAScaledEstimate) {
  const int n = 120;
  const io::Trajectory gt = make_trajectory(moving_pose, n);
  io::Trajectory est;
  for (const io::StampedPose& p : gt) {
    est.emplace_back(p.timestamp_s, SE3(p.T_w_c().quaternion(), 0.4 * p.t_w_c + Vec3d(1, 1, 1)));
  }
  AteOptions o;
  EXPECT_GT(compute_ate(gt, est, o).stats_m.rmse, 0.05);
  o.align_scale = true;
  const AteResult scaled = compute_ate(gt, est, o);
  EXPECT_LT(scaled.stats_m.rmse, 1e-9);
  EXPECT_NEAR(scaled.alignment.scale, 2.5, 1e-9);
  // The --scale factor does the same by hand.
  o.align_scale = false;
  o.scale = 2.5;
  EXPECT_LT(compute_ate(gt, est, o).stats_m.rmse, 1e-9);
}

TEST(AteTest, OffsetShiftsTheEstimatesStamps) {
  const int n = 100;
  const io::Trajectory gt = make_trajectory(moving_pose, n);
  io::Trajectory est = gt;
  for (io::StampedPose& p : est) p.timestamp_s -= 100.0;  // another clock
  EXPECT_THROW(compute_ate(gt, est), InputError);
  AteOptions o;
  o.offset_s = 100.0;
  EXPECT_EQ(compute_ate(gt, est, o).stats_m.count, static_cast<std::size_t>(n));
  RpeOptions ro;
  ro.offset_s = 100.0;
  EXPECT_NEAR(compute_rpe(gt, est, ro).trans_m.max, 0.0, 1e-12);
}

TEST(AteTest, LostFramesAreIgnoredByAte) {
  const int n = 100;
  const io::Trajectory gt = make_trajectory(moving_pose, n);
  io::Trajectory est;
  for (int k = 0; k < n; k += 3) est.push_back(gt[static_cast<std::size_t>(k)]);
  const AteResult r = compute_ate(gt, est);
  EXPECT_EQ(r.stats_m.count, est.size());
  EXPECT_LT(r.stats_m.max, 1e-9);
}

}  // namespace
}  // namespace ddl::eval
