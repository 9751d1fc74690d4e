#include "ddl/pipeline/system.h"

#include <spdlog/spdlog.h>

#include "ddl/core/error.h"

namespace ddl::pipeline {

void SystemConfig::validate() const {
  if (keyframe_queue_capacity == 0) {
    throw ConfigError::for_key("pipeline.keyframe_queue_capacity", "must be at least 1");
  }
  tracking.validate();
  mapping.validate();
  loop.validate();
}

System::System(const SystemConfig& config, const camera::PinholeCamera& camera,
               std::shared_ptr<const vocabulary::Vocabulary> vocabulary)
    : config_(config),
      camera_(camera),
      vocabulary_(std::move(vocabulary)),
      database_(std::make_shared<vocabulary::BowDatabase>()),
      map_(std::make_shared<map::Map>()) {
  config_.validate();
  camera_.validate();
  if (!vocabulary_ || vocabulary_->empty()) throw Error("System: the vocabulary is empty");
  tracker_ =
      std::make_unique<tracking::Tracker>(config_.tracking, camera_, map_, vocabulary_, database_);
  mapper_ = std::make_unique<mapping::LocalMapper>(config_.mapping, camera_, map_, vocabulary_,
                                                   database_);
  loop_closer_ =
      std::make_unique<loop::LoopCloser>(config_.loop, camera_, map_, vocabulary_, database_);
  if (config_.mode == RunMode::kThreaded) {
    mapping_queue_ =
        std::make_unique<BoundedQueue<map::KeyFramePtr>>(config_.keyframe_queue_capacity);
    loop_queue_ = std::make_unique<BoundedQueue<map::KeyFramePtr>>(config_.keyframe_queue_capacity);
    mapping_thread_ = std::thread([this] { mapping_worker(); });
    loop_thread_ = std::thread([this] { loop_worker(); });
  }
}

System::~System() {
  try {
    shutdown_workers();
  } catch (...) {
    spdlog::error("System: error while shutting down the workers");
  }
}

tracking::TrackingResult System::process(const io::RgbdFrame& frame, const cv::Mat& dynamic_mask) {
  if (finished_) throw Error("System::process called after finish()");
  rethrow_worker_error();

  tracking::MappingStatus status;
  if (config_.mode == RunMode::kThreaded) {
    status.queued_keyframes = mapping_queue_->size();
    status.accepts_keyframes = status.queued_keyframes == 0 && !mapper_busy_.load();
  }
  Stopwatch watch;
  tracking::TrackingResult result = tracker_->track(frame, dynamic_mask, status);
  timings_.record("tracking", watch.elapsed_ms());
  for (const auto& [stage, ms] : result.stage_ms) timings_.record("tracking." + stage, ms);

  ++stats_.frames;
  if (result.state == tracking::TrackingState::kOk ||
      result.state == tracking::TrackingState::kRelocalized) {
    ++stats_.frames_tracked;
  } else if (result.state == tracking::TrackingState::kLost) {
    ++stats_.frames_lost;
  }
  if (result.state == tracking::TrackingState::kRelocalized) ++stats_.relocalizations;

  if (result.new_keyframe) {
    ++stats_.keyframes_created;
    if (config_.mode == RunMode::kDeterministic) {
      handle_keyframe_inline(result.new_keyframe);
    } else {
      abort_local_ba_.store(true);
      if (!mapping_queue_->push(result.new_keyframe)) rethrow_worker_error();
    }
  }
  return result;
}

void System::handle_keyframe_inline(const map::KeyFramePtr& keyframe) {
  Stopwatch watch;
  map::KeyFramePtr kept = mapper_->process(keyframe, nullptr);
  timings_.record("local_mapping", watch.elapsed_ms());
  if (!kept) return;
  watch.reset();
  loop_closer_->process(kept);
  timings_.record("loop_closing", watch.elapsed_ms());
}

void System::mapping_worker() {
  try {
    while (auto keyframe = mapping_queue_->pop()) {
      mapper_busy_.store(true);
      abort_local_ba_.store(false);
      Stopwatch watch;
      map::KeyFramePtr kept = mapper_->process(*keyframe, &abort_local_ba_);
      timings_.record("local_mapping", watch.elapsed_ms());
      mapper_busy_.store(false);
      if (kept && !loop_queue_->push(kept)) break;
    }
  } catch (...) {
    mapper_busy_.store(false);
    store_error(std::current_exception());
  }
  loop_queue_->close();
}

void System::loop_worker() {
  try {
    while (auto keyframe = loop_queue_->pop()) {
      Stopwatch watch;
      loop_closer_->process(*keyframe);
      timings_.record("loop_closing", watch.elapsed_ms());
    }
  } catch (...) {
    store_error(std::current_exception());
  }
}

void System::store_error(std::exception_ptr error) {
  {
    std::lock_guard lock(error_mutex_);
    if (!worker_error_) worker_error_ = std::move(error);
  }
  failed_.store(true);
  // Unblock everyone: the producer sees push() fail, the other worker drains and ends.
  if (mapping_queue_) mapping_queue_->close();
  if (loop_queue_) loop_queue_->close();
}

void System::rethrow_worker_error() {
  if (!failed_.load()) return;
  shutdown_workers();
  std::lock_guard lock(error_mutex_);
  if (worker_error_) std::rethrow_exception(worker_error_);
}

void System::shutdown_workers() {
  if (mapping_queue_) mapping_queue_->close();
  if (mapping_thread_.joinable()) mapping_thread_.join();
  if (loop_queue_) loop_queue_->close();
  if (loop_thread_.joinable()) loop_thread_.join();
  if (loop_closer_) loop_closer_->stop();
}

void System::finish() {
  if (finished_) return;
  finished_ = true;
  shutdown_workers();
  if (loop_closer_) loop_closer_->wait_for_global_ba();
  std::lock_guard lock(error_mutex_);
  if (worker_error_) std::rethrow_exception(worker_error_);
}

io::Trajectory System::camera_trajectory() const { return tracker_->camera_trajectory(); }

io::Trajectory System::keyframe_trajectory() const {
  io::Trajectory out;
  for (const map::KeyFramePtr& kf : map_->keyframes()) {
    out.emplace_back(kf->timestamp_s(), kf->T_w_c());
  }
  return out;
}

SystemStatistics System::statistics() const {
  SystemStatistics s = stats_;
  s.keyframes = map_->keyframe_count();
  s.map_points = map_->map_point_count();
  s.loops_closed = loop_closer_->loops_closed();
  return s;
}

}  // namespace ddl::pipeline
