#include "ddl/pipeline/dense_mapper.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <functional>
#include <opencv2/imgproc.hpp>
#include <vector>

#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"
#include "ddl/tracking/trajectory_recorder.h"

#ifdef __linux__
#include <sys/resource.h>
#include <unistd.h>
#endif

namespace ddl::pipeline {
namespace fs = std::filesystem;
namespace {

/// A keyframe's colour, depth and exclusion images, every `pixel_step`-th pixel of the camera's.
struct ScanImages {
  cv::Mat bgr;
  cv::Mat depth_m;
  cv::Mat exclude;
  int pixel_step = 1;
};

/// `images` with only the pixels the octree integrates when they hold every pixel and the
/// octree's `stride` is above 1; as they are otherwise (they share the buffers).
ScanImages at_octree_stride(ScanImages images, int stride) {
  if (images.pixel_step != 1 || stride <= 1) return images;
  const octomap::KeyframeScan c =
      octomap::subsampled({0, SE3(), images.bgr, images.depth_m, images.exclude}, stride);
  return {c.bgr, c.depth_m, c.exclude_mask, stride};
}

}  // namespace

void DenseMapperConfig::validate() const {
  if (queue_capacity == 0) throw ConfigError::for_key("dense.queue_capacity", "must be >= 1");
  if (thread_nice < 0 || thread_nice > 19) {
    throw ConfigError::for_key("dense.thread_nice", "must be in 0..19");
  }
  if (mask_border_px < 0 || mask_border_px > 50) {
    throw ConfigError::for_key("dense.mask_border_px", "must be in 0..50");
  }
  if (octree_delay_keyframes < 0 || octree_delay_keyframes > 1000) {
    throw ConfigError::for_key("dense.octree_delay_keyframes", "must be in 0..1000");
  }
  inpainting.validate();
  octree.validate();
}

DenseMapper::DenseMapper(const DenseMapperConfig& config, const camera::PinholeCamera& camera,
                         std::shared_ptr<const map::Map> map)
    : config_(config), camera_(camera), map_(std::move(map)) {
  config_.validate();
  if (config_.octomap_enabled)
    octree_ = std::make_unique<octomap::OctreeMap>(config_.octree, camera_);
  if (!config_.save_inpainted_dir.empty()) {
    create_folder(config_.save_inpainted_dir, "the inpainted frames");
  }
  if (config_.threaded || config_.deterministic_thread) {
    queue_ = std::make_unique<BoundedQueue<Item>>(config_.queue_capacity);
    thread_ = std::thread([this] { worker(); });
  }
}

DenseMapper::~DenseMapper() {
  if (queue_) queue_->close();
  if (thread_.joinable()) thread_.join();
}

void DenseMapper::preload(std::vector<map::DenseScan> scans) {
  if (finished_ || submitted_any_) {
    throw Error("DenseMapper::preload after a keyframe was submitted or after finish()");
  }
  if (!octree_ || scans.empty()) return;
  std::vector<Stored> entries;
  entries.reserve(scans.size());
  for (map::DenseScan& scan : scans) {
    map::KeyFramePtr anchor = map_->keyframe(scan.anchor);
    if (!anchor) {
      throw Error(fmt::format("dense scan anchored to keyframe {}, which the map does not hold",
                              scan.anchor));
    }
    if (scan.pixel_step != 1 && scan.pixel_step != config_.octree.pixel_stride) {
      throw ConfigError::for_key(
          "dense.octree.pixel_stride",
          fmt::format("is {}, but the loaded map's dense scans were taken every {} pixels; run "
                      "with the same stride to extend its octree",
                      config_.octree.pixel_stride, scan.pixel_step));
    }
    Stored s;
    s.keyframe = std::move(anchor);
    s.T_anchor_c = scan.T_anchor_c;
    ScanImages images = at_octree_stride(
        {std::move(scan.bgr), std::move(scan.depth_m), std::move(scan.exclude), scan.pixel_step},
        config_.octree.pixel_stride);
    s.bgr = std::move(images.bgr);
    s.depth_m = std::move(images.depth_m);
    s.exclude = std::move(images.exclude);
    s.pixel_step = images.pixel_step;
    entries.push_back(std::move(s));
  }
  if (!queue_) {
    add_preloaded(std::move(entries));
    return;
  }
  std::optional<DensePoseSnapshot> snapshot;
  if (!config_.threaded) {
    for (const Stored& s : entries) submitted_.push_back(s.keyframe);
    snapshot = take_snapshot(submitted_);
  }
  if (!queue_->push(Item(Preloaded{std::move(entries), std::move(snapshot)})) && error_) {
    std::rethrow_exception(error_);
  }
}

void DenseMapper::add_preloaded(std::vector<Stored> scans) {
  const std::size_t n = scans.size();
  stored_.insert(stored_.begin() + static_cast<std::ptrdiff_t>(loaded_),
                 std::make_move_iterator(scans.begin()), std::make_move_iterator(scans.end()));
  loaded_ += n;
  integrate_due(0);
  std::lock_guard lock(stats_mutex_);
  stats_.scans_loaded += n;
}

void DenseMapper::submit(DenseKeyframe keyframe) {
  if (finished_) throw Error("DenseMapper::submit after finish()");
  submitted_any_ = true;
  if (!queue_) {
    process(std::move(keyframe));
    return;
  }
  std::optional<DensePoseSnapshot> snapshot;
  if (!config_.threaded) {
    submitted_.push_back(keyframe.keyframe);
    snapshot = take_snapshot(submitted_);
  }
  if (!queue_->push(Item(Submitted{std::move(keyframe), std::move(snapshot)})) && error_) {
    std::rethrow_exception(error_);
  }
}

DensePoseSnapshot DenseMapper::take_snapshot(const std::vector<map::KeyFramePtr>& keyframes) const {
  DensePoseSnapshot snapshot;
  map_->read_consistent([&] {
    snapshot.big_change_index = map_->big_change_index();
    for (const map::KeyFramePtr& kf : keyframes) {
      snapshot.T_w_c.emplace(kf->id(), tracking::resolved_T_w_c(kf));
    }
  });
  return snapshot;
}

int DenseMapper::big_change_index() const {
  return snapshot_ ? snapshot_->big_change_index : map_->big_change_index();
}

std::vector<SE3> DenseMapper::poses_of(const std::vector<map::KeyFramePtr>& keyframes) const {
  std::vector<SE3> poses(keyframes.size());
  if (snapshot_) {
    for (std::size_t i = 0; i < keyframes.size(); ++i) {
      poses[i] = snapshot_->T_w_c.at(keyframes[i]->id());
    }
    return poses;
  }
  map_->read_consistent([&] {
    for (std::size_t i = 0; i < keyframes.size(); ++i) {
      poses[i] = tracking::resolved_T_w_c(keyframes[i]);
    }
  });
  return poses;
}

void DenseMapper::reset() {
  if (finished_) throw Error("DenseMapper::reset after finish()");
  if (!queue_) {
    drop_stored();
    return;
  }
  std::optional<DensePoseSnapshot> snapshot;
  if (!config_.threaded) {
    submitted_.clear();
    snapshot = take_snapshot({});
  }
  if (!queue_->push(Item(ResetRequest{std::move(snapshot)})) && error_) {
    std::rethrow_exception(error_);
  }
}

void DenseMapper::handle(Item item) {
  // snapshot_ points into `item`: cleared on every way out, an exception included.
  struct ClearSnapshot {
    const DensePoseSnapshot*& snapshot;
    ~ClearSnapshot() { snapshot = nullptr; }
  } clear{snapshot_};
  if (auto* submitted = std::get_if<Submitted>(&item)) {
    snapshot_ = submitted->snapshot ? &*submitted->snapshot : nullptr;
    process(std::move(submitted->keyframe));
  } else if (auto* preloaded = std::get_if<Preloaded>(&item)) {
    snapshot_ = preloaded->snapshot ? &*preloaded->snapshot : nullptr;
    add_preloaded(std::move(preloaded->scans));
  } else {
    auto& reset = std::get<ResetRequest>(item);
    snapshot_ = reset.snapshot ? &*reset.snapshot : nullptr;
    drop_stored();
  }
}

void DenseMapper::drop_stored() {
  stored_.clear();
  loaded_ = 0;
  if (octree_) octree_->clear();
  seen_big_change_ = big_change_index();
  std::lock_guard lock(stats_mutex_);
  ++stats_.resets;
}

void DenseMapper::worker() {
#ifdef __linux__
  // Per-thread on Linux: the nice value belongs to the thread id, not the process.
  if (config_.thread_nice != 0 &&
      setpriority(PRIO_PROCESS, static_cast<id_t>(gettid()), config_.thread_nice) != 0) {
    spdlog::warn("dense mapping: could not lower the thread priority ({})", std::strerror(errno));
  }
#endif
  try {
    while (auto item = queue_->pop()) handle(std::move(*item));
  } catch (...) {
    error_ = std::current_exception();
    queue_->close();
  }
}

void DenseMapper::finish() {
  if (finished_) return;
  finished_ = true;
  if (queue_) queue_->close();
  if (thread_.joinable()) thread_.join();
  if (error_) std::rethrow_exception(error_);
  // Poses keep moving until the last global BA, and local BA refines each keyframe after it was
  // integrated (in deterministic mode the dense stage runs before local mapping sees the
  // keyframe): integrate once more at the final poses when they moved.
  // Timed like the rebuilds and integrations during the run (until stop 32 these were counted
  // in octree_rebuilds but missing from timing_ms).
  if (!octree_) return;
  Stopwatch watch;
  if (map_->big_change_index() != seen_big_change_) {
    rebuild_octree(0);
    timings_.record("octomap_rebuild", watch.elapsed_ms());
    return;
  }
  if (integrate_due(0) > 0) timings_.record("octomap", watch.elapsed_ms());  // delayed keyframes
  if (poses_moved_since_integration()) {
    watch.reset();
    rebuild_octree(0);
    timings_.record("octomap_rebuild", watch.elapsed_ms());
  }
}

std::size_t DenseMapper::integrate_due(std::size_t keep_back) {
  if (stored_.size() <= keep_back) return 0;
  const std::size_t due = stored_.size() - keep_back;
  std::vector<std::size_t> todo;
  for (std::size_t i = 0; i < due; ++i) {
    if (!stored_[i].integrated) todo.push_back(i);
  }
  if (todo.empty()) return 0;
  std::vector<map::KeyFramePtr> keyframes;
  for (const std::size_t i : todo) keyframes.push_back(stored_[i].keyframe);
  const std::vector<SE3> poses = poses_of(keyframes);
  for (std::size_t k = 0; k < todo.size(); ++k) {
    Stored& s = stored_[todo[k]];
    s.T_w_c_integrated = camera_pose(s, poses[k]);
  }
  for (const std::size_t i : todo) {
    Stored& s = stored_[i];
    octree_->integrate(
        {s.keyframe->id(), s.T_w_c_integrated, s.bgr, s.depth_m, s.exclude, s.pixel_step});
    s.integrated = true;
  }
  return todo.size();
}

bool DenseMapper::poses_moved_since_integration() const {
  const double tolerance_m = 0.25 * config_.octree.resolution_m;
  // A rotation by angle a moves a point at the octree's range by a * range.
  const double tolerance_rad = tolerance_m / config_.octree.max_range_m;
  double max_m = 0.0;
  double max_rad = 0.0;
  map_->read_consistent([&] {
    for (const Stored& s : stored_) {
      if (!s.integrated) continue;
      const SE3 T_now_then =
          camera_pose(s, tracking::resolved_T_w_c(s.keyframe)).inverse() * s.T_w_c_integrated;
      max_m = std::max(max_m, T_now_then.translation().norm());
      max_rad = std::max(max_rad, T_now_then.rotation_angle());
    }
  });
  const bool moved = max_m > tolerance_m || max_rad > tolerance_rad;
  spdlog::info(
      "dense mapping: keyframes moved by up to {:.4f} m and {:.3f} deg since they went "
      "into the octree{}",
      max_m, max_rad * 180.0 / M_PI, moved ? ": rebuilding it at the final poses" : "");
  return moved;
}

void DenseMapper::process(DenseKeyframe item) {
  Stopwatch watch;
  Stored stored;
  stored.keyframe = item.keyframe;
  stored.bgr = item.bgr;
  stored.depth_m = item.depth_m;
  const cv::Mat mask =
      item.dynamic_mask.empty() ? cv::Mat::zeros(item.bgr.size(), CV_8UC1) : item.dynamic_mask;
  if (config_.inpainting_enabled && cv::countNonZero(mask) > 0) {
    // Loaded scans (at the front of stored_) are no sources.
    const std::size_t n = std::min(stored_.size() - loaded_, source_window());
    // The poses of the keyframe and its sources, in one reading: local BA and loop correction
    // write poses under the map's update lock, and a repair from two world frames would stay in
    // the stored images. A culled keyframe is at its parent-resolved pose, since its own froze
    // when it was culled: for sources since 2026-11-26; for the keyframe itself since 2026-11-27
    // (culled while queued, it was repaired at the frozen pose, across a loop correction).
    std::vector<map::KeyFramePtr> keyframes{item.keyframe};
    for (std::size_t k = 0; k < n; ++k)
      keyframes.push_back(stored_[stored_.size() - 1 - k].keyframe);
    const std::vector<SE3> poses = poses_of(keyframes);  // the keyframe's, then its sources'
    const SE3& T_w_c = poses[0];
    std::vector<inpainting::SourceView> sources;
    for (std::size_t k = 0; k < n; ++k) {
      const Stored& s = stored_[stored_.size() - 1 - k];  // newest first
      sources.push_back({poses[k + 1], s.bgr, s.depth_m, s.exclude, s.repaired, s.blocks});
    }
    const inpainting::InpaintingResult r = inpainting::inpaint(
        item.bgr, item.depth_m, mask, T_w_c.inverse(), sources, camera_, config_.inpainting);
    stored.bgr = r.bgr;
    stored.depth_m = r.depth_m;
    stored.unfilled = r.unfilled;
    stored.repaired = mask & ~r.unfilled;
    std::lock_guard lock(stats_mutex_);
    stats_.masked_pixels += r.masked_pixels;
    stats_.filled_pixels += r.filled_pixels;
    stats_.image_filled_pixels += cv::countNonZero(r.image_filled);
  } else {
    // Without inpainting the dynamic pixels are simply left out of the map.
    stored.unfilled = mask;
  }
  // stored.unfilled may be the caller's mask itself, which tracking and dynamic removal keep:
  // the border goes into a new buffer (assigning a MatExpr to a Mat that shares its buffer
  // writes through it - that grew the keyframe masks the dynamic memory keeps, before 2026-11-26).
  if (config_.mask_border_px > 0 && cv::countNonZero(mask) > 0) {
    cv::Mat grown;
    const int k = 2 * config_.mask_border_px + 1;
    cv::dilate(mask, grown, cv::getStructuringElement(cv::MORPH_ELLIPSE, {k, k}));
    cv::Mat exclude;
    cv::bitwise_or(stored.unfilled, grown & (mask == 0), exclude);
    stored.exclude = exclude;
  } else {
    stored.exclude = stored.unfilled;
  }
  if (config_.inpainting_enabled && config_.inpainting.skip_unreachable_blocks) {
    // Computed once here instead of in each later repair that uses this keyframe as a source.
    stored.blocks = std::make_shared<const inpainting::DepthBlocks>(
        inpainting::depth_blocks(stored.depth_m, stored.exclude, stored.repaired));
  }
  timings_.record("inpainting", watch.elapsed_ms());

  if (!config_.save_inpainted_dir.empty()) {
    const fs::path dir(config_.save_inpainted_dir);
    const std::string stem = fmt::format("{:.6f}", item.keyframe->timestamp_s());
    saved_images_.write_png(dir / (stem + "_rgb.png"), stored.bgr);
    cv::Mat depth16;
    stored.depth_m.convertTo(depth16, CV_16UC1, camera_.depth_factor);
    saved_images_.write_png(dir / (stem + "_depth.png"), depth16);
    saved_images_.write_png(dir / (stem + "_unfilled.png"), stored.unfilled);
    // The mask the repair worked on: filled pixels = mask and not unfilled (eval-dense).
    saved_images_.write_png(dir / (stem + "_mask.png"), mask);
  }

  if (octree_) {
    watch.reset();
    const int big_change = big_change_index();
    // Per-keyframe integration and whole-map rebuilds are timed apart: a rebuild costs all
    // keyframes at once.
    const auto delay = static_cast<std::size_t>(config_.octree_delay_keyframes);
    stored_.push_back(std::move(stored));
    if (big_change != seen_big_change_) {
      rebuild_octree(delay);
      timings_.record("octomap_rebuild", watch.elapsed_ms());
    } else if (integrate_due(delay) > 0) {
      timings_.record("octomap", watch.elapsed_ms());
    }
  } else {
    stored_.push_back(std::move(stored));
  }
  compact_old_keyframes();
  std::lock_guard lock(stats_mutex_);
  ++stats_.keyframes;
}

std::size_t DenseMapper::source_window() const {
  return config_.inpainting_enabled ? static_cast<std::size_t>(config_.inpainting.num_keyframes +
                                                               config_.inpainting.extra_keyframes)
                                    : 0;
}

void DenseMapper::compact_old_keyframes() {
  const std::size_t sources = source_window();
  const std::size_t old_end = stored_.size() > sources ? stored_.size() - sources : 0;
  for (std::size_t i = 0; i < old_end; ++i) {
    Stored& s = stored_[i];
    if (s.pixel_step > 1 || (s.bgr.empty() && s.depth_m.empty())) continue;
    if (octree_) {
      ScanImages images = at_octree_stride({s.bgr, s.depth_m, s.exclude, s.pixel_step},
                                           config_.octree.pixel_stride);
      s.bgr = std::move(images.bgr);
      s.depth_m = std::move(images.depth_m);
      s.exclude = std::move(images.exclude);
      s.pixel_step = images.pixel_step;
    } else {
      s.bgr.release();
      s.depth_m.release();
      s.exclude.release();
    }
    s.unfilled.release();
    s.repaired.release();
    s.blocks.reset();
  }
  std::size_t bytes = 0;
  const auto size_of = [](const cv::Mat& m) { return m.empty() ? 0 : m.total() * m.elemSize(); };
  for (const Stored& s : stored_) {
    bytes += size_of(s.bgr) + size_of(s.depth_m) + size_of(s.exclude) + size_of(s.repaired);
    if (s.unfilled.data != s.exclude.data) bytes += size_of(s.unfilled);
  }
  std::lock_guard lock(stats_mutex_);
  stats_.peak_stored_image_bytes = std::max(stats_.peak_stored_image_bytes, bytes);
}

void DenseMapper::rebuild_octree(std::size_t keep_back) {
  seen_big_change_ = big_change_index();
  octree_->clear();
  for (Stored& s : stored_) s.integrated = false;
  integrate_due(keep_back);
  std::lock_guard lock(stats_mutex_);
  ++stats_.octree_rebuilds;
}

std::vector<std::string> DenseMapper::write_outputs(const std::string& dir,
                                                    std::vector<std::string>& errors) const {
  std::vector<std::string> written;
  if (!octree_) return written;
  create_folder(dir, "the octree map");
  const fs::path d(dir);
  const auto write = [&](const char* name, const std::function<void(const std::string&)>& fn) {
    const std::string path = (d / name).string();
    try {
      fn(path);
      written.push_back(path);
    } catch (const Error& e) {
      errors.push_back(e.what());
    }
  };
  write("map.ot", [&](const std::string& p) { octree_->write_ot(p); });
  write("map.bt", [&](const std::string& p) { octree_->write_bt(p); });
  write("map.ply", [&](const std::string& p) { octree_->write_ply(p); });
  // The map lives in the SLAM world frame, the first camera's: its y points down (roughly, as
  // the camera was held), so up is -y and the top view looks along +y, with the first camera's
  // viewing direction (z) pointing up the image.
  const Vec3d kUp(0.0, -1.0, 0.0);
  write("map_top.png", [&](const std::string& p) {
    io::write_png(p, octree_->render(false, kUp), "the map's top view");
  });
  write("map_oblique.png", [&](const std::string& p) {
    io::write_png(p, octree_->render(true, kUp), "the map's oblique view");
  });
  return written;
}

std::vector<map::DenseScan> DenseMapper::dense_scans() const {
  if (!finished_) throw Error("DenseMapper::dense_scans before finish()");
  std::vector<map::DenseScan> scans;
  if (!octree_) return scans;
  const int stride = config_.octree.pixel_stride;
  map_->read_consistent([&] {
    for (const Stored& s : stored_) {
      if (s.depth_m.empty()) continue;
      map::KeyFramePtr anchor = s.keyframe;
      while (anchor->is_bad() && anchor->parent()) anchor = anchor->parent();
      map::DenseScan scan;
      scan.anchor = anchor->id();
      scan.T_anchor_c = tracking::resolved_T_w_c(anchor).inverse() *
                        camera_pose(s, tracking::resolved_T_w_c(s.keyframe));
      ScanImages images = at_octree_stride({s.bgr, s.depth_m, s.exclude, s.pixel_step}, stride);
      scan.bgr = std::move(images.bgr);
      scan.depth_m = std::move(images.depth_m);
      scan.exclude = std::move(images.exclude);
      scan.pixel_step = images.pixel_step;
      scans.push_back(std::move(scan));
    }
  });
  return scans;
}

DenseStats DenseMapper::stats() const {
  std::lock_guard lock(stats_mutex_);
  return stats_;
}

}  // namespace ddl::pipeline
