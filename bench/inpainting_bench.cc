// Micro-benchmark of the background inpainting (docs/dense.md):
//   ddl_bench_inpainting --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// The scene is syn_walking_xyz rendered in process (silhouette people, no files needed): the
// keyframe to repair and the 15 + extra_keyframes keyframes before it, every 6th frame, at their
// true poses, the repaired keyframe with its true dynamic mask grown by 4 px. Each source has its
// depth blocks computed beforehand (as the dense stage gives them) and is either observed (its
// true dynamic mask grown by 12 px is the pixels not to use) or repaired as the dense stage keeps
// its keyframes: its mask grown by 4 px shows the true background and is its repaired mask, the
// band of 8 px around it is not to be used. Arguments: the frame of the repaired keyframe,
// dense.inpainting.skip_unreachable_blocks (1 = default), dense.inpainting.extra_keyframes and
// whether the sources are repaired.

#include <benchmark/benchmark.h>

#include <opencv2/imgproc.hpp>
#include <vector>

#include "ddl/inpainting/background_inpainter.h"
#include "ddl/synthetic/sequence.h"

namespace {

using ddl::inpainting::InpaintingConfig;
using ddl::inpainting::SourceView;

struct Keyframe {
  ddl::SE3 T_w_c;
  cv::Mat bgr;
  cv::Mat depth_m;
  cv::Mat dynamic_mask;
  cv::Mat background_bgr;
  cv::Mat background_depth_m;
};

cv::Mat grown(const cv::Mat& mask, int px) {
  cv::Mat out;
  cv::dilate(mask, out, cv::getStructuringElement(cv::MORPH_ELLIPSE, {2 * px + 1, 2 * px + 1}));
  return out;
}

Keyframe render(const ddl::synthetic::SequenceSource& source, std::size_t index) {
  const ddl::synthetic::FrameData frame = source.render_frame(index);
  Keyframe k;
  k.T_w_c = frame.T_w_c;
  k.bgr = frame.rgb;
  frame.depth_raw.convertTo(k.depth_m, CV_32F, 1.0 / source.camera().depth_factor);
  k.dynamic_mask = frame.dynamic_mask;
  k.background_bgr = frame.background_rgb;
  frame.background_depth_raw.convertTo(k.background_depth_m, CV_32F,
                                       1.0 / source.camera().depth_factor);
  return k;
}

void BM_Inpaint(benchmark::State& state) {
  const ddl::synthetic::Preset& preset = ddl::synthetic::find_preset("syn_walking_xyz");
  const auto source = ddl::synthetic::make_sequence_source(preset.config);
  const auto target_index = static_cast<std::size_t>(state.range(0));
  InpaintingConfig config;
  config.skip_unreachable_blocks = state.range(1) != 0;
  config.extra_keyframes = static_cast<int>(state.range(2));
  const Keyframe target = render(*source, target_index);
  std::vector<SourceView> sources;  // newest first
  for (int k = 1; k <= config.num_keyframes + config.extra_keyframes; ++k) {
    const Keyframe kf = render(*source, target_index - static_cast<std::size_t>(6 * k));
    SourceView view{kf.T_w_c, kf.bgr, kf.depth_m, grown(kf.dynamic_mask, 12), cv::Mat(), nullptr};
    if (state.range(3) != 0) {
      const cv::Mat repaired = grown(kf.dynamic_mask, 4);
      view.bgr = kf.bgr.clone();
      view.depth_m = kf.depth_m.clone();
      kf.background_bgr.copyTo(view.bgr, repaired);
      kf.background_depth_m.copyTo(view.depth_m, repaired);
      view.exclude_mask = view.exclude_mask & ~repaired;
      view.repaired_mask = repaired;
    }
    view.blocks = std::make_shared<const ddl::inpainting::DepthBlocks>(
        ddl::inpainting::depth_blocks(view.depth_m, view.exclude_mask, view.repaired_mask));
    sources.push_back(view);
  }
  const cv::Mat mask = grown(target.dynamic_mask, 4);
  int filled = 0;
  for (auto _ : state) {
    const auto result =
        ddl::inpainting::inpaint(target.bgr, target.depth_m, mask, target.T_w_c.inverse(), sources,
                                 source->camera(), config);
    filled = result.filled_pixels;
    benchmark::DoNotOptimize(filled);
  }
  state.counters["masked_px"] = cv::countNonZero(mask);
  state.counters["filled_px"] = filled;
}
BENCHMARK(BM_Inpaint)
    ->Args({300, 1, 25, 0})
    ->Args({300, 1, 0, 0})
    ->Args({300, 0, 25, 0})
    ->Args({500, 1, 25, 0})
    ->Args({500, 1, 0, 0})
    ->Args({300, 1, 25, 1})
    ->Args({300, 1, 0, 1})
    ->Args({300, 0, 25, 1})
    ->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
