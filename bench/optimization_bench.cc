// Micro-benchmarks of ddl::optimization: pose-only BA (called by tracking for every frame) and
// local BA (called by local mapping for every keyframe) on synthetic RGB-D scenes.
//
//   build/<dir>/bench/ddl_bench_optimization --benchmark_repetitions=5
//       --benchmark_report_aggregates_only=true

#include <benchmark/benchmark.h>

#include <cmath>
#include <random>
#include <vector>

#include "ddl/optimization/bundle_adjustment.h"
#include "ddl/optimization/pose_optimization.h"

namespace {

using ddl::Mat3d;
using ddl::SE3;
using ddl::Vec2d;
using ddl::Vec3d;
namespace opt = ddl::optimization;

const opt::CameraIntrinsics kCamera{517.306408, 516.469215, 318.643040, 255.313989, 40.0};

opt::Measurement measure(const SE3& T_c_w, const Vec3d& p_w, bool stereo, int level,
                         std::mt19937& rng) {
  const Vec3d p_c = T_c_w * p_w;
  std::normal_distribution<double> noise(0.0, 1.0);
  opt::Measurement m;
  m.uv_px = Vec2d(kCamera.fx * p_c.x() / p_c.z() + kCamera.cx + noise(rng),
                  kCamera.fy * p_c.y() / p_c.z() + kCamera.cy + noise(rng));
  m.stereo = stereo;
  m.u_right_px = m.uv_px.x() - kCamera.bf / p_c.z() + noise(rng);
  m.inv_sigma2 = std::pow(1.2, -2.0 * level);
  return m;
}

Vec3d visible_point(const SE3& T_c_w, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0.0, 640.0), v(0.0, 480.0), z(0.5, 6.0);
  const double depth = z(rng);
  return T_c_w.inverse() * Vec3d((u(rng) - kCamera.cx) / kCamera.fx * depth,
                                 (v(rng) - kCamera.cy) / kCamera.fy * depth, depth);
}

SE3 perturb(const SE3& T, double t_m, double angle_rad, std::mt19937& rng) {
  std::normal_distribution<double> n(0.0, 1.0);
  return SE3(Mat3d(Eigen::AngleAxisd(angle_rad, Vec3d(n(rng), n(rng), n(rng)).normalized())),
             t_m * Vec3d(n(rng), n(rng), n(rng)).normalized()) *
         T;
}

/// Pose-only BA with state.range(0) observations: 80% RGB-D (3-dof) residuals, 1 px noise,
/// 10% gross outliers, start 2 cm / 1 deg off (a motion-model prediction).
void BM_PoseOnlyBA(benchmark::State& state) {
  std::mt19937 rng(42);
  const SE3 T_true(Mat3d(Eigen::AngleAxisd(0.3, Vec3d(0.1, 1.0, 0.2).normalized())),
                   Vec3d(0.2, -0.1, 0.5));
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> level(0, 7);
  std::vector<opt::PoseObservation> observations;
  for (int i = 0; i < state.range(0); ++i) {
    opt::PoseObservation obs;
    obs.p_w = visible_point(T_true, rng);
    obs.measurement = measure(T_true, obs.p_w, unit(rng) < 0.8, level(rng), rng);
    if (unit(rng) < 0.1) obs.measurement.uv_px += Vec2d(30.0 + 50.0 * unit(rng), 40.0);
    observations.push_back(obs);
  }
  const SE3 initial = perturb(T_true, 0.02, 1.0 * M_PI / 180.0, rng);
  const opt::OptimizerConfig config;
  int inliers = 0;
  for (auto _ : state) {
    const opt::PoseOptimizationResult r =
        opt::optimize_pose(kCamera, initial, observations, config);
    inliers = r.num_inliers;
    benchmark::DoNotOptimize(r.T_c_w);
  }
  state.counters["inliers"] = inliers;
}
BENCHMARK(BM_PoseOnlyBA)->Arg(400)->Unit(benchmark::kMillisecond);

/// Local BA: state.range(0) keyframes (2 of them fixed), 1000 points seen by 2-6 keyframes each,
/// 80% RGB-D residuals, 1 px noise, 5% outliers; poses 2 cm / 0.5 deg and points 2 cm off.
void BM_LocalBA(benchmark::State& state) {
  std::mt19937 rng(7);
  const int num_kf = static_cast<int>(state.range(0));
  opt::BundleAdjustmentProblem problem;
  problem.camera = kCamera;
  std::vector<SE3> truth;
  for (int k = 0; k < num_kf; ++k) {
    const SE3 T_w_c(Mat3d(Eigen::AngleAxisd(0.02 * k, Vec3d::UnitY())), Vec3d(0.05 * k, 0, 0));
    truth.push_back(T_w_c.inverse());
    problem.keyframes.push_back(
        {k < 2 ? truth[k] : perturb(truth[k], 0.02, 0.5 * M_PI / 180, rng), k < 2});
  }
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> first(0, num_kf - 2), span(2, 6), level(0, 7);
  std::normal_distribution<double> n(0.0, 0.02);
  for (int p = 0; p < 1000; ++p) {
    const int k0 = first(rng);
    const Vec3d p_w = visible_point(truth[k0], rng);
    problem.points_w.push_back(p_w + Vec3d(n(rng), n(rng), n(rng)));
    for (int k = k0; k < std::min(num_kf, k0 + span(rng)); ++k) {
      if ((truth[k] * p_w).z() < 0.3) continue;
      opt::Measurement m = measure(truth[k], p_w, unit(rng) < 0.8, level(rng), rng);
      if (unit(rng) < 0.05) m.uv_px += Vec2d(40.0, -30.0);
      problem.observations.push_back({static_cast<std::size_t>(k), static_cast<std::size_t>(p), m});
    }
  }
  const opt::OptimizerConfig config;
  for (auto _ : state) {
    const opt::BundleAdjustmentResult r = opt::local_bundle_adjustment(problem, config);
    benchmark::DoNotOptimize(r.points_w.data());
  }
  state.counters["observations"] = static_cast<double>(problem.observations.size());
}
BENCHMARK(BM_LocalBA)->Arg(10)->Arg(20)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
