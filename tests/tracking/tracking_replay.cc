// Measurement tool (not a test, not built by default): runs a TUM-layout sequence through the
// Tracker alone (no local mapping, no loop closing) and prints ATE against the ground truth and
// the median per-frame tracking time per stage.
//
//   tracking_replay <sequence dir> <camera (builtin name or yaml)> <vocabulary file>
//                   [--associate] [--frames N] [--out trajectory.txt] [--train-every K]
//                   [--min-frames M] [--mapper] [--bow-levels-up L] [--verbose]
//                   [--live-out trajectory.txt]
//
// --associate: each new keyframe goes through the minimal local-mapping stand-in of the tests
// (observations, covisibility, BoW database), as ORB-SLAM2's ProcessNewKeyFrame does first.
// --live-out FILE: the poses as tracked (TrackingResult::T_w_c), before later map corrections.
// --verbose: one line per frame, and the ATE error of every frame.
// --mapper: each new keyframe is processed inline by mapping::LocalMapper (when built with it);
// local mapping counts as busy for the frames that arrive at 30 Hz while it works.
// --bow-levels-up L: tracking.frame.bow_levels_up (default 4).
// --min-frames M: tracking.keyframes.min_frames (frames between keyframes while mapping is idle).
// When the vocabulary file does not exist, a vocabulary (k = 10, L = 6) is trained from every
// K-th frame of the sequence (default 5) and saved there.

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <memory>
#include <opencv2/imgproc.hpp>
#include <string>
#include <vector>

#include "ddl/config/camera_config.h"
#include "ddl/core/error.h"
#include "ddl/core/timing.h"
#include "ddl/eval/ate.h"
#include "ddl/eval/rpe.h"
#include "ddl/features/orb_extractor.h"
#include "ddl/io/trajectory_io.h"
#include "ddl/io/tum_dataset.h"
#ifdef DDL_REPLAY_HAS_MAPPER
#include "ddl/mapping/local_mapper.h"
#endif
#include "ddl/tracking/tracker.h"
#include "ddl/vocabulary/vocabulary_training.h"
#include "tracking_test_support.h"

namespace {

using namespace ddl;

std::shared_ptr<const vocabulary::Vocabulary> load_or_train(const std::string& path,
                                                            const io::TumDataset& dataset,
                                                            std::size_t every) {
  if (std::filesystem::exists(path)) {
    return std::make_shared<const vocabulary::Vocabulary>(vocabulary::Vocabulary::load(path));
  }
  spdlog::info("training a vocabulary from every {}th frame into {}", every, path);
  features::OrbExtractor extractor(features::OrbExtractorConfig{});
  std::vector<cv::Mat> descriptors;
  for (std::size_t i = 0; i < dataset.size(); i += every) {
    const io::RgbdFrame frame = dataset.frame(i);
    cv::Mat grey;
    cv::cvtColor(frame.rgb, grey, cv::COLOR_BGR2GRAY);
    descriptors.push_back(extractor.extract(grey).descriptors);
  }
  vocabulary::VocabularyConfig config;
  config.threads = 2;
  vocabulary::Vocabulary voc = vocabulary::train_vocabulary(descriptors, config);
  voc.save(path);
  return std::make_shared<const vocabulary::Vocabulary>(std::move(voc));
}

}  // namespace

int main(int argc, char** argv) {
  if (argc < 4) {
    fmt::print(stderr,
               "usage: {} <sequence dir> <camera> <vocabulary file> [--associate] [--frames N] "
               "[--out file] [--train-every K] [--min-frames M]\n",
               argv[0]);
    return 2;
  }
  try {
    const std::string dir = argv[1];
    bool associate = false;
    std::size_t max_frames = 0;
    std::size_t train_every = 5;
    int min_frames = 0;
    int bow_levels_up = 4;
    bool with_mapper = false;
    bool verbose = false;
    std::string live_out;
    io::Trajectory live;
    std::string out;
    for (int a = 4; a < argc; ++a) {
      const std::string arg = argv[a];
      if (arg == "--associate") {
        associate = true;
      } else if (arg == "--frames" && a + 1 < argc) {
        max_frames = std::stoul(argv[++a]);
      } else if (arg == "--out" && a + 1 < argc) {
        out = argv[++a];
      } else if (arg == "--live-out" && a + 1 < argc) {
        live_out = argv[++a];
      } else if (arg == "--verbose") {
        verbose = true;
      } else if (arg == "--mapper") {
        with_mapper = true;
      } else if (arg == "--bow-levels-up" && a + 1 < argc) {
        bow_levels_up = std::stoi(argv[++a]);
      } else if (arg == "--min-frames" && a + 1 < argc) {
        min_frames = std::stoi(argv[++a]);
      } else if (arg == "--train-every" && a + 1 < argc) {
        train_every = std::stoul(argv[++a]);
      } else {
        throw ddl::Error("unknown argument " + arg);
      }
    }
    spdlog::set_level(std::getenv("DDL_DEBUG") ? spdlog::level::debug : spdlog::level::warn);
    const io::TumDataset dataset(dir, config::load_camera(argv[2]));
    const auto voc = load_or_train(argv[3], dataset, train_every);
    auto map = std::make_shared<map::Map>();
    auto database = std::make_shared<vocabulary::BowDatabase>();
    tracking::TrackerConfig config;
    config.keyframes.min_frames = min_frames;
    config.frame.bow_levels_up = bow_levels_up;
    tracking::Tracker tracker(config, dataset.camera(), map, voc, database);

#ifdef DDL_REPLAY_HAS_MAPPER
    std::unique_ptr<mapping::LocalMapper> mapper;
    if (with_mapper) {
      mapping::LocalMapperConfig mapper_config;
      mapper_config.bow_levels_up = config.frame.bow_levels_up;
      mapper = std::make_unique<mapping::LocalMapper>(mapper_config, dataset.camera(), map, voc,
                                                      database);
    }
#else
    if (with_mapper) throw ddl::Error("built without ddl::mapping");
#endif
    std::size_t busy_until = 0;
    std::vector<double> mapper_ms;
    const std::size_t n = max_frames > 0 ? std::min(max_frames, dataset.size()) : dataset.size();
    std::vector<double> cpu, local_kfs, local_points, projected, total, features, initial, local,
        keyframe, update, search, pose;
    std::size_t tracked = 0;
    std::size_t keyframes = 0;
    std::size_t lost_events = 0;
    std::size_t relocalizations = 0;
    tracking::TrackingState previous = tracking::TrackingState::kNotInitialized;
    for (std::size_t i = 0; i < n; ++i) {
      const io::RgbdFrame frame = dataset.frame(i);
      const double cpu_start = thread_cpu_ms();
      tracking::MappingStatus status;
      status.accepts_keyframes = i >= busy_until;
      const tracking::TrackingResult r = tracker.track(frame, cv::Mat(), status);
      cpu.push_back(thread_cpu_ms() - cpu_start);
      local_kfs.push_back(static_cast<double>(tracker.local_map().keyframes().size()));
      local_points.push_back(static_cast<double>(tracker.local_map().points().size()));
      projected.push_back(static_cast<double>(tracker.local_map().projected_count()));
      if (r.new_keyframe) {
        ++keyframes;
        if (associate) tracking::testing::associate_keyframe(r.new_keyframe, *database);
#ifdef DDL_REPLAY_HAS_MAPPER
        if (mapper) {
          // Mapping runs inline; as in a threaded real-time run it is "busy" (no keyframes while
          // idle-only criteria apply) for the frames a 30 Hz camera delivers meanwhile.
          const Stopwatch watch;
          mapper->process(r.new_keyframe, nullptr);
          mapper_ms.push_back(watch.elapsed_ms());
          busy_until = i + 1 + static_cast<std::size_t>(mapper_ms.back() / (1000.0 / 30.0));
        }
#endif
      }
      tracked += r.tracked() ? 1 : 0;
      if (r.T_w_c) live.emplace_back(r.timestamp_s, *r.T_w_c);
      if (verbose) {
        fmt::print("{:4d} {:<18} inliers {:4d} features {:4d}{} local kfs {} pts {} ms {:.1f}\n", i,
                   tracking::to_string(r.method), r.num_inliers, r.num_features,
                   r.new_keyframe ? " KF" : "   ", tracker.local_map().keyframes().size(),
                   tracker.local_map().points().size(), r.timings.total_ms);
      }
      if (r.state == tracking::TrackingState::kLost && previous != tracking::TrackingState::kLost) {
        ++lost_events;
      }
      relocalizations += r.state == tracking::TrackingState::kRelocalized ? 1 : 0;
      previous = r.state;
      total.push_back(r.timings.total_ms);
      features.push_back(r.timings.features_ms);
      initial.push_back(r.timings.initial_pose_ms);
      local.push_back(r.timings.local_map_ms);
      keyframe.push_back(r.timings.keyframe_ms);
      if (r.timings.local_map_ms > 0.0) {
        update.push_back(r.timings.local_map_update_ms);
        search.push_back(r.timings.local_map_search_ms);
        pose.push_back(r.timings.local_map_pose_ms);
      }
    }
    const io::Trajectory trajectory = tracker.camera_trajectory();
    if (!out.empty()) io::write_tum_trajectory(out, trajectory);
    if (!live_out.empty()) io::write_tum_trajectory(live_out, live);
    fmt::print(
        "frames {}  tracked {} ({:.1f}%)  lost events {}  relocalizations {}  keyframes {}  "
        "map points {}\n",
        n, tracked, 100.0 * tracked / n, lost_events, relocalizations, keyframes,
        map->map_point_count());
    fmt::print(
        "median ms: total {:.2f}  features {:.2f}  initial pose {:.2f}  local map {:.2f}  "
        "keyframe {:.2f}   (mean total {:.2f})\n",
        median(total), median(features), median(initial), median(local), median(keyframe), [&] {
          double s = 0;
          for (double t : total) s += t;
          return s / static_cast<double>(total.size());
        }());
    fmt::print("median thread CPU ms per frame: {:.2f}\n", median(cpu));
    if (!mapper_ms.empty()) {
      fmt::print("local mapping: median {:.1f} ms per keyframe, {} keyframes in the map\n",
                 median(mapper_ms), map->keyframe_count());
    }
    fmt::print("local map medians: {} keyframes, {} points, {} predicted in view\n",
               median(local_kfs), median(local_points), median(projected));
    fmt::print("local map medians ms: update {:.2f}  search {:.2f}  pose BA {:.2f}\n",
               median(update), median(search), median(pose));
    if (dataset.groundtruth_path()) {
      const eval::AteResult ate =
          eval::compute_ate(io::read_tum_trajectory(*dataset.groundtruth_path()), trajectory);
      fmt::print("ATE rmse {:.4f} m  mean {:.4f}  median {:.4f}  max {:.4f}  ({} pairs)\n",
                 ate.stats_m.rmse, ate.stats_m.mean, ate.stats_m.median, ate.stats_m.max,
                 ate.stats_m.count);
      std::string segments;
      for (std::size_t k = 0; k < ate.errors_m.size(); k += 50) {
        double worst = 0.0;
        for (std::size_t j = k; j < std::min(k + 50, ate.errors_m.size()); ++j) {
          worst = std::max(worst, ate.errors_m[j]);
        }
        segments += fmt::format(" {:.3f}", worst);
      }
      fmt::print("ATE max per 50 frames [m]:{}\n", segments);
      eval::RpeOptions rpe_options;
      rpe_options.delta = 1.0;
      rpe_options.delta_unit = eval::DeltaUnit::kFrames;
      const eval::RpeResult rpe = eval::compute_rpe(
          io::read_tum_trajectory(*dataset.groundtruth_path()), trajectory, rpe_options);
      fmt::print("RPE per frame: rmse {:.4f} m {:.3f} deg\n", rpe.trans_m.rmse, rpe.rot_deg.rmse);
      if (verbose) {
        for (const eval::RpePair& p : rpe.pairs) {
          fmt::print("rpe {:.6f} {:.4f} {:.3f}\n", p.stamp_est_0_s, p.trans_error_m,
                     p.rot_error_rad * 180.0 / M_PI);
        }
        for (std::size_t k = 0; k < ate.errors_m.size(); ++k) {
          fmt::print("err {:4d} {:.6f} {:.4f}\n", k, ate.stamps_est_s[k], ate.errors_m[k]);
        }
      }
    }
  } catch (const std::exception& e) {
    fmt::print(stderr, "error: {}\n", e.what());
    return 2;
  }
  return 0;
}
