// Micro-benchmarks of the dynamic front end's kernels: the picture veto and the free-space check.
// The picture veto (dynamics::drop_pictures, docs/dynamics.md "Pictures"):
//   ddl_bench_dynamics --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// The depth image is a frame of syn_walking_rpy rendered in process (silhouette people, no files
// needed). Masks: the frame's true dynamic mask (people, which the veto keeps: the usual case),
// the same plus a 160 x 120 px region on the background (a picture, flooded to its full reach),
// and a field of 2 x 2 px specks every `gap` pixels over the whole image (the worst case, bounded
// by dynamic.picture_veto.max_flood_pixels). Argument 0: the frame; argument 1: the mask kind
// (0 people, 1 people + picture, 2 specks); argument 2: the speck gap in pixels.

#include <benchmark/benchmark.h>

#include <opencv2/imgproc.hpp>

#include "ddl/dynamics/free_space_check.h"
#include "ddl/dynamics/picture_veto.h"
#include "ddl/synthetic/sequence.h"

namespace {

void BM_DropPictures(benchmark::State& state) {
  const ddl::synthetic::Preset& preset = ddl::synthetic::find_preset("syn_walking_rpy");
  const auto source = ddl::synthetic::make_sequence_source(preset.config);
  const ddl::synthetic::FrameData frame =
      source->render_frame(static_cast<std::size_t>(state.range(0)));
  cv::Mat depth_m;
  frame.depth_raw.convertTo(depth_m, CV_32F, 1.0 / source->camera().depth_factor);
  cv::Mat mask = frame.dynamic_mask.clone();
  if (state.range(1) == 1) {
    // The picture: the 160 x 120 window with the fewest people pixels of a coarse grid.
    cv::Rect best;
    int fewest = -1;
    for (int v = 0; v + 120 <= mask.rows; v += 40) {
      for (int u = 0; u + 160 <= mask.cols; u += 40) {
        const cv::Rect r(u, v, 160, 120);
        const int n = cv::countNonZero(frame.dynamic_mask(r));
        if (fewest < 0 || n < fewest) fewest = n, best = r;
      }
    }
    mask(best).setTo(255);
  } else if (state.range(1) == 2) {
    mask.setTo(0);
    const int gap = static_cast<int>(state.range(2));
    for (int v = 0; v + 2 <= mask.rows; v += gap) {
      for (int u = 0; u + 2 <= mask.cols; u += gap) mask(cv::Rect(u, v, 2, 2)).setTo(255);
    }
  }
  const ddl::dynamics::PictureVetoConfig config;
  ddl::dynamics::PictureVetoStats stats;
  for (auto _ : state) {
    const cv::Mat out = ddl::dynamics::drop_pictures(mask, depth_m, config, &stats);
    benchmark::DoNotOptimize(out.data);
  }
  state.counters["regions"] = stats.regions;
  state.counters["dropped"] = stats.dropped;
  state.counters["unjudged"] = stats.unjudged;
}
BENCHMARK(BM_DropPictures)
    ->Args({300, 0, 0})
    ->Args({300, 1, 0})
    ->Args({600, 0, 0})
    ->Args({600, 1, 0})
    ->Args({300, 2, 8})
    ->Args({300, 2, 32})
    ->Unit(benchmark::kMillisecond);

}  // namespace

// The free-space check (docs/dynamics.md, "Free-space check"): frame 300 of syn_walking_rpy
// against 25 views of frames 0-288 (every 12th, ground-truth poses, true masks), default
// settings. Argument 0: the stage (0 view selection among the 25, 1 votes of the 24 chosen,
// 2 votes to mask, 3 judging the true mask's regions).
void BM_FreeSpaceCheck(benchmark::State& state) {
  const ddl::synthetic::Preset& preset = ddl::synthetic::find_preset("syn_walking_rpy");
  const auto source = ddl::synthetic::make_sequence_source(preset.config);
  const ddl::camera::PinholeCamera& camera = source->camera();
  const auto depth_of = [&](const ddl::synthetic::FrameData& f) {
    cv::Mat depth_m;
    f.depth_raw.convertTo(depth_m, CV_32F, 1.0 / camera.depth_factor);
    return depth_m;
  };
  const ddl::dynamics::FreeSpaceConfig config;
  std::vector<ddl::dynamics::FreeSpaceView> all;
  std::vector<ddl::SE3> poses;
  for (std::size_t k = 0; k <= 288; k += 12) {
    const ddl::synthetic::FrameData f = source->render_frame(k);
    all.push_back(
        ddl::dynamics::prepare_free_space_view(f.T_w_c, depth_of(f), f.dynamic_mask, config));
    poses.push_back(f.T_w_c);
  }
  const ddl::synthetic::FrameData frame = source->render_frame(300);
  const cv::Mat depth_m = depth_of(frame);
  const ddl::SE3 T_c_w = frame.T_w_c.inverse();
  std::vector<ddl::dynamics::FreeSpaceView> views;
  for (const std::size_t k :
       ddl::dynamics::select_free_space_views(depth_m, T_c_w, poses, camera, config)) {
    views.push_back(all[k]);
  }
  const ddl::dynamics::FreeSpaceVotes votes =
      ddl::dynamics::free_space_votes(depth_m, T_c_w, views, camera, config);
  ddl::dynamics::FreeSpaceStats stats;
  for (auto _ : state) {
    switch (state.range(0)) {
      case 0:
        benchmark::DoNotOptimize(
            ddl::dynamics::select_free_space_views(depth_m, T_c_w, poses, camera, config));
        break;
      case 1:
        benchmark::DoNotOptimize(
            ddl::dynamics::free_space_votes(depth_m, T_c_w, views, camera, config).stride);
        break;
      case 2:
        benchmark::DoNotOptimize(
            ddl::dynamics::free_space_mask(depth_m, votes, config, &stats).data);
        break;
      default:
        benchmark::DoNotOptimize(
            ddl::dynamics::drop_static_regions(frame.dynamic_mask, votes, config, &stats).data);
    }
  }
  state.counters["views"] = static_cast<double>(views.size());
  state.counters["regions"] = stats.regions;
}
BENCHMARK(BM_FreeSpaceCheck)->Arg(0)->Arg(1)->Arg(2)->Arg(3)->Unit(benchmark::kMillisecond);

BENCHMARK_MAIN();
