// Measurement tool (not a benchmark): CNN time per frame and mask quality of the segmenter on a
// synthetic sequence with ground-truth dynamic masks (<sequence>/dynamic_mask/<stamp>.png).
//   ddl_segmentation_eval <sequence> <model.onnx> <width> <height> [threads] [frames] [interval]
//     [reuse_dilation_px]
// Prints the median and mean inference time and the mean IoU / precision / recall of the dynamic
// mask against the truth over the frames whose truth is not empty. With interval N > 1 the CNN
// runs on every N-th frame and the frames between reuse its mask grown by reuse_dilation_px (the
// `dynamic.segmentation_interval` schedule); their IoU is reported separately.

#include <time.h>

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <opencv2/core.hpp>
#include <opencv2/core/utility.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "ddl/core/timing.h"
#include "ddl/dynamics/mask_fusion.h"
#include "ddl/segmentation/segmenter.h"

namespace fs = std::filesystem;

namespace {

/// CPU time of the calling thread: the cost of the CNN with num_threads = 1 (all of it runs on
/// this thread), independent of other processes competing for the cores.
double thread_cpu_ms() {
  timespec t{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) * 1e3 + static_cast<double>(t.tv_nsec) * 1e-6;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 5) {
    std::fprintf(stderr,
                 "usage: %s SEQUENCE MODEL WIDTH HEIGHT [THREADS] [FRAMES] [INTERVAL] "
                 "[REUSE_DILATION_PX]\n",
                 argv[0]);
    return 2;
  }
  const fs::path sequence = argv[1];
  ddl::segmentation::SegmenterConfig config;
  config.model_path = argv[2];
  config.input_width = std::stoi(argv[3]);
  config.input_height = std::stoi(argv[4]);
  config.num_threads = argc > 5 ? std::stoi(argv[5]) : 1;
  const std::size_t max_frames = argc > 6 ? std::stoul(argv[6]) : 100;
  const int interval = argc > 7 ? std::stoi(argv[7]) : 1;
  const int reuse_dilation_px = argc > 8 ? std::stoi(argv[8]) : 0;
  cv::setNumThreads(config.num_threads);

  std::vector<fs::path> images;
  for (const auto& entry : fs::directory_iterator(sequence / "rgb")) images.push_back(entry.path());
  std::sort(images.begin(), images.end());
  if (images.size() > max_frames) images.resize(max_frames);

  auto segmenter = ddl::segmentation::make_segmenter(config, ".");
  ddl::TimingStats timings;
  double iou_cnn = 0.0, precision = 0.0, recall = 0.0, iou_reused = 0.0, recall_reused = 0.0;
  int n_cnn = 0, n_reused = 0;
  cv::Mat last;
  for (std::size_t k = 0; k < images.size(); ++k) {
    const cv::Mat bgr = cv::imread(images[k].string(), cv::IMREAD_COLOR);
    const cv::Mat truth = cv::imread((sequence / "dynamic_mask" / images[k].filename()).string(),
                                     cv::IMREAD_GRAYSCALE);
    const bool run_cnn = static_cast<int>(k) % interval == 0;
    cv::Mat mask;
    if (run_cnn) {
      ddl::Stopwatch watch;
      const double cpu_start_ms = thread_cpu_ms();
      mask = segmenter->segment(bgr, images[k].string()).dynamic_mask;
      timings.record("cnn", watch.elapsed_ms());
      timings.record("cnn_cpu", thread_cpu_ms() - cpu_start_ms);
      last = mask;
    } else {
      mask = ddl::dynamics::feature_exclusion_mask(last, reuse_dilation_px);
    }
    if (truth.empty() || cv::countNonZero(truth) == 0) continue;
    const ddl::dynamics::MaskScore s = ddl::dynamics::score_mask(mask, truth);
    if (run_cnn) {
      iou_cnn += s.iou;
      precision += s.precision;
      recall += s.recall;
      ++n_cnn;
    } else {
      iou_reused += s.iou;
      recall_reused += s.recall;
      ++n_reused;
    }
  }
  const auto all = timings.summary();
  const ddl::StageSummary summary = all.at("cnn");
  const ddl::StageSummary cpu = all.at("cnn_cpu");
  std::printf(
      "%dx%d threads %d: %zu frames, CNN wall median %.1f ms mean %.1f ms, thread CPU median "
      "%.1f ms; CNN frames: IoU %.3f "
      "precision %.3f recall %.3f (%d frames)",
      config.input_width, config.input_height, config.num_threads, images.size(), summary.median_ms,
      summary.mean_ms, cpu.median_ms, n_cnn ? iou_cnn / n_cnn : 0.0,
      n_cnn ? precision / n_cnn : 0.0, n_cnn ? recall / n_cnn : 0.0, n_cnn);
  if (n_reused > 0) {
    std::printf("; reused frames (interval %d, dilation %d px): IoU %.3f recall %.3f (%d frames)",
                interval, reuse_dilation_px, iou_reused / n_reused, recall_reused / n_reused,
                n_reused);
  }
  std::printf("\n");
  return 0;
}
