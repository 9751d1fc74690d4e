// Micro-benchmark of the octree map (docs/dense.md):
//   ddl_bench_octomap --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
// The scans are keyframes of syn_walking_xyz rendered in process (silhouette people, no files
// needed): every 6th frame from frame 200, at its true pose, the true dynamic mask grown by 12 px
// as the pixels not to insert (as the dense stage gives them). One iteration integrates them all
// into a new map with the default settings; the argument is the number of scans (time per scan =
// time / scans).

#include <benchmark/benchmark.h>

#include <opencv2/imgproc.hpp>
#include <vector>

#include "ddl/octomap/octree_map.h"
#include "ddl/synthetic/sequence.h"

namespace {

using ddl::octomap::KeyframeScan;

std::vector<KeyframeScan> render_scans(const ddl::synthetic::SequenceSource& source, int count) {
  std::vector<KeyframeScan> scans;
  for (int k = 0; k < count; ++k) {
    const ddl::synthetic::FrameData frame =
        source.render_frame(200 + 6 * static_cast<std::size_t>(k));
    KeyframeScan scan;
    scan.keyframe_id = static_cast<std::uint64_t>(k);
    scan.T_w_c = frame.T_w_c;
    scan.bgr = frame.rgb;
    frame.depth_raw.convertTo(scan.depth_m, CV_32F, 1.0 / source.camera().depth_factor);
    cv::dilate(frame.dynamic_mask, scan.exclude_mask,
               cv::getStructuringElement(cv::MORPH_ELLIPSE, {25, 25}));
    scans.push_back(scan);
  }
  return scans;
}

void BM_OctreeIntegrate(benchmark::State& state) {
  const auto source =
      ddl::synthetic::make_sequence_source(ddl::synthetic::find_preset("syn_walking_xyz").config);
  const std::vector<KeyframeScan> scans = render_scans(*source, static_cast<int>(state.range(0)));
  std::size_t occupied = 0;
  for (auto _ : state) {
    ddl::octomap::OctreeMap map({}, source->camera());
    for (const KeyframeScan& scan : scans) map.integrate(scan);
    occupied = map.stats().occupied_leaves;
    benchmark::DoNotOptimize(occupied);
  }
  state.counters["occupied_leaves"] = static_cast<double>(occupied);
}
BENCHMARK(BM_OctreeIntegrate)->Arg(20)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
