#include "ddl/pipeline/system.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"
#include "ddl/dynamics/mask_fusion.h"

namespace ddl::pipeline {

void SystemConfig::validate() const {
  if (keyframe_queue_capacity == 0) {
    throw ConfigError::for_key("keyframe_queue_capacity", "must be at least 1");
  }
  if (deterministic_mapping_busy_frames < 0) {
    throw ConfigError::for_key("deterministic_mapping_busy_frames", "must be >= 0");
  }
  if (threaded_lockstep_keyframes < 0) {
    throw ConfigError::for_key("threaded_lockstep_keyframes", "must be >= 0");
  }
  tracking.validate();
  mapping.validate();
  loop.validate();
  dynamic.validate();
  dense.validate();
  // One camera, one virtual baseline: the frames store u_r = u - bf / z with tracking's value,
  // and mapping and loop closing predict u_r with theirs. A difference puts every RGB-D residual
  // off by delta_bf / z (5 px at 2 m for 10) and silently turns close points into outliers.
  for (const auto& [key, value] :
       {std::pair<const char*, double>{"mapping.bf", mapping.bf}, {"loop.bf", loop.bf}}) {
    if (value != tracking.frame.bf) {
      throw ConfigError::for_key(
          key, fmt::format("is {} but tracking.frame.bf is {}: the three bf keys must be equal",
                           value, tracking.frame.bf));
    }
  }
  // The direct index: mapping lists the features of a keyframe whose bag of words tracking left
  // empty at its own depth, and BoW matching compares node ids, so two depths share no node
  // (review, stop 26).
  if (mapping.bow_levels_up != tracking.frame.bow_levels_up) {
    throw ConfigError::for_key(
        "mapping.bow_levels_up",
        fmt::format("is {} but tracking.frame.bow_levels_up is {}: the two must be equal",
                    mapping.bow_levels_up, tracking.frame.bow_levels_up));
  }
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
  loop::LoopCloserConfig loop_config = config_.loop;
  loop_config.global_ba_in_background = config_.mode == RunMode::kThreaded;
  loop_closer_ =
      std::make_unique<loop::LoopCloser>(loop_config, camera_, map_, vocabulary_, database_);
  dynamic_ = std::make_unique<DynamicFrontEnd>(config_.dynamic, camera_, config_.shared_dir);
  memory_anchor_ = std::make_unique<MapCorrectionFollower>(map_);
  depth_aligner_ = std::make_unique<DepthTimeAligner>(camera_, config_.align_depth_in_time);
  DenseMapperConfig dense_config = config_.dense;
  dense_config.threaded = config_.mode == RunMode::kThreaded;
  dense_ = std::make_unique<DenseMapper>(dense_config, camera_, map_);
  if (config_.save_masks && !config_.output_dir.empty()) {
    for (const char* part : {"cnn", "geometry", "memory", "free_space"}) {
      create_folder(std::filesystem::path(config_.output_dir) / "masks" / part, "the masks");
    }
  }
  if (config_.mode == RunMode::kThreaded) {
    mapping_queue_ =
        std::make_unique<BoundedQueue<map::KeyFramePtr>>(config_.keyframe_queue_capacity);
    // Unbounded: the mapping worker must never block on it. A loop correction waits for the
    // mapping queue to drain (LocalMappingGate) while the loop thread takes nothing from here;
    // the mapping queue's bound limits what flows in.
    loop_queue_ =
        std::make_unique<BoundedQueue<map::KeyFramePtr>>(std::numeric_limits<std::size_t>::max());
    loop_closer_->set_mapping_pause(
        {[this] { mapping_gate_.pause(); }, [this] { mapping_gate_.resume(); }});
    mapping_thread_ = std::thread([this] { mapping_worker(); });
    loop_thread_ = std::thread([this] { loop_worker(); });
  }
}

System::~System() {
  try {
    shutdown_workers(/*wait_for_global_ba=*/false);
  } catch (...) {
    spdlog::error("System: error while shutting down the workers");
  }
}

std::optional<SE3> System::previous_pose(std::uint64_t frame_changes) const {
  if (!last_T_c_w_ || last_pose_frame_changes_ != frame_changes) return std::nullopt;
  return last_T_c_w_;
}

std::optional<SE3> System::constant_velocity_pose(std::uint64_t frame_changes) const {
  const std::optional<SE3> previous = previous_pose(frame_changes);
  if (!previous || !velocity_) return previous;
  return *velocity_ * *previous;
}

CnnMask System::segment(const io::RgbdFrame& frame) {
  if (!dynamic_->enabled()) return {};
  return dynamic_->cnn_mask(frame);
}

cv::Mat System::remove_moving_features(io::RgbdFrame& frame, tracking::Frame& current,
                                       DynamicMasks& masks) {
  const bool use_memory = dynamic_->memory_enabled();
  const bool use_free_space = config_.dynamic.free_space.enabled;
  if ((!config_.dynamic.use_geometry && !use_memory && !use_free_space) || !last_reference_) {
    return {};
  }
  if (last_reference_->is_bad()) {
    // Culled since the last frame (threaded mode): no low-cost pose, nothing to check this frame.
    if (config_.dynamic.use_geometry) ++stats_.geometry_checks_without_reference;
    if (use_free_space) ++stats_.free_space_checks_skipped;
    return {};
  }
  // Loop closing may move the keyframes between the low-cost pose and the reading of the
  // references' poses (threaded mode); the check then compares in two different world frames.
  const std::uint64_t stops_before = mapping_gate_.stop_sequence();
  // The previous pose and the memory's points are in the world frame of this count.
  const std::uint64_t frame_changes = map_->frame_change_count();
  const Stopwatch watch;
  std::optional<SE3> T_c_w = tracker_->low_cost_pose(current);
  timings_.record("low_cost_tracking", watch.elapsed_ms());
  if (T_c_w) {
    ++stats_.geometry_checks_low_cost;
  } else {
    T_c_w = constant_velocity_pose(frame_changes);
    if (!T_c_w) return {};
    ++stats_.geometry_checks_predicted;
  }
  if (depth_aligner_->active()) {
    // The motion from the previous frame to this one's pose: the depth, captured between the
    // two or just before (tum1: 20-40 ms before the colour), is interpolated, not extrapolated.
    const Stopwatch align_watch;
    const std::optional<SE3> previous = previous_pose(frame_changes);
    DepthAlignment alignment;
    frame.depth_m = depth_aligner_->align(
        frame, previous ? std::optional<SE3>(*T_c_w * previous->inverse()) : std::nullopt,
        frame.timestamp_s - last_pose_stamp_s_, &alignment);
    if (alignment.moved) {
      ++stats_.depth_images_aligned;
      timings_.record("depth_alignment", align_watch.elapsed_ms());
    }
  }
  if (config_.dynamic.use_geometry) {
    // Multi-view geometry at the low-cost pose against the reference keyframe and the keyframes
    // that share most points with it (the best overlap; DDL-SLAM Algorithm 1).
    const Stopwatch geometry_watch;
    std::vector<dynamics::ReferenceView> references;
    map_->read_consistent([&] {
      std::vector<map::KeyFramePtr> keyframes{last_reference_};
      for (auto& kf : last_reference_->best_covisibles(
               static_cast<std::size_t>(config_.dynamic.geometry.max_reference_keyframes - 1))) {
        keyframes.push_back(std::move(kf));
      }
      references = dynamic_->reference_views(keyframes);
    });
    if (!LocalMappingGate::unchanged(stops_before, mapping_gate_.stop_sequence())) {
      ++stats_.geometry_checks_skipped;
      references.clear();  // no geometry mask for this frame
    } else if (std::none_of(references.begin(), references.end(),
                            [](const dynamics::ReferenceView& view) {
                              return !view.depth_image_m.empty();
                            })) {
      ++stats_.geometry_checks_without_reference;  // the check tests nothing
    }
    masks.geometry = dynamic_->geometry_mask(frame, *T_c_w, references, &masks.geometry_stats,
                                             previous_pose(frame_changes));
    const dynamics::GeometryCheckStats& g = masks.geometry_stats;
    if (g.implausible) ++stats_.geometry_checks_implausible;
    spdlog::debug(
        "frame {}: geometry check tested {} points, {} seeds, motion {:.1f} px, median residual "
        "{:.2f} tau{}",
        frame.index, g.points_tested - g.points_skipped_parallax, g.points_dynamic,
        g.median_motion_px, g.median_residual_ratio,
        g.implausible ? " (implausible: no mask)" : "");
    masks.geometry_ms = geometry_watch.elapsed_ms();
    timings_.record("geometry_check", masks.geometry_ms);
  }
  if (use_free_space) {
    // The frame's points against many earlier keyframes: in space they saw empty, something moved.
    const Stopwatch free_space_watch;
    std::vector<dynamics::FreeSpaceView> views;
    map_->read_consistent([&] { views = dynamic_->free_space_views(frame, *T_c_w); });
    if (!LocalMappingGate::unchanged(stops_before, mapping_gate_.stop_sequence())) {
      ++stats_.free_space_checks_skipped;
      views.clear();  // the poses may be in two world frames: no free-space mask for this frame
    }
    masks.free_space =
        dynamic_->free_space_mask(frame, *T_c_w, views, &masks.free_space_votes,
                                  &masks.free_space_stats, &masks.free_space_regions);
    const dynamics::FreeSpaceStats& f = masks.free_space_stats;
    spdlog::debug("frame {}: free-space check: {} views, {} samples, {} dynamic, {} regions",
                  frame.index, f.views, f.samples, f.samples_dynamic, f.regions);
    timings_.record("free_space_check", free_space_watch.elapsed_ms());
  }
  if (use_memory) {
    // Where people the CNN found in the last frames still are (it misses those cut by the border).
    const Stopwatch memory_watch;
    if (const std::optional<SE3> T_new_old = memory_anchor_->correction()) {
      spdlog::debug("frame {}: dynamic memory moved with the map by {:.3f} m", frame.index,
                    T_new_old->translation().norm());
      dynamic_->move_dynamic_surfaces(*T_new_old);
    }
    // A correction since the low-cost pose (threaded mode) moved the memory into a world frame
    // the pose is not in: no recall this frame (review, stop 25).
    if (map_->frame_change_count() == frame_changes) {
      masks.memory = dynamic_->memory_mask(frame, *T_c_w, &masks.memory_stats);
    }
    timings_.record("dynamic_memory", memory_watch.elapsed_ms());
  }
  cv::Mat moved = masks.geometry;
  if (config_.dynamic.memory.drop_features) moved = dynamics::combine_masks(moved, masks.memory);
  if (config_.dynamic.free_space.drop_features) {
    // The grown parts only with grow_drops_features: a growth that leaked onto the desk would
    // take the features a fast rotation needs (the composite lost track on fr1_rpy's fast part).
    moved = dynamics::combine_masks(moved, config_.dynamic.free_space.grow_drops_features
                                               ? masks.free_space
                                               : masks.free_space_regions);
  }
  cv::Mat exclusion = dynamic_->exclusion_mask(moved);
  const Stopwatch drop_watch;
  tracker_->exclude_features(current, exclusion);
  timings_.record("geometry_feature_removal", drop_watch.elapsed_ms());
  return exclusion;
}

map::MapFileContents System::load_map(const std::string& path) {
  if (stats_.frames > 0 || map_->keyframe_count() > 0) {
    throw Error(fmt::format("{}: a map is loaded before the first frame, into an empty map", path));
  }
  const auto accept = [&](const map::MapFileInfo& info) {
    if (info.descriptor_tag != vocabulary_->descriptor_tag() ||
        info.vocabulary_words != vocabulary_->word_count()) {
      throw InputError::at(
          path, fmt::format("built with another vocabulary ({} words, descriptor tag {:016x}); "
                            "this run's has {} words and tag {:016x}",
                            info.vocabulary_words, info.descriptor_tag, vocabulary_->word_count(),
                            vocabulary_->descriptor_tag()));
    }
    const auto close = [](double a, double b) { return std::abs(a - b) <= 1e-6 * std::abs(b); };
    if (info.image_width != camera_.width || info.image_height != camera_.height ||
        !close(info.fx, camera_.fx) || !close(info.fy, camera_.fy) || !close(info.cx, camera_.cx) ||
        !close(info.cy, camera_.cy)) {
      throw InputError::at(
          path, fmt::format("built with another camera ({}x{}, fx {} fy {} cx {} cy {}); this "
                            "run's camera '{}' is {}x{}, fx {} fy {} cx {} cy {}",
                            info.image_width, info.image_height, info.fx, info.fy, info.cx, info.cy,
                            camera_.name, camera_.width, camera_.height, camera_.fx, camera_.fy,
                            camera_.cx, camera_.cy));
    }
  };
  const Stopwatch watch;
  const map::MapFileContents contents = map::load_map_file(path, *map_, accept);
  if (contents.keyframes == 0) throw InputError::at(path, "the map holds no keyframe");
  for (const map::KeyFramePtr& keyframe : map_->keyframes()) {
    keyframe->compute_bow(*vocabulary_, config_.tracking.frame.bow_levels_up);
    database_->add(keyframe->id(), keyframe->bow());
    // The stored depth images become the geometry check's references again.
    if (const auto it = contents.images.find(keyframe->id()); it != contents.images.end()) {
      dynamic_->remember_loaded_keyframe(keyframe, it->second.depth_m, it->second.dynamic_mask);
    }
  }
  // The scans the dense stage kept in the run that made the map: its octree grows on them.
  dense_->preload(contents.dense_scans);
  tracker_->start_in_loaded_map();
  map_loaded_ = true;
  stats_.keyframes_loaded = contents.keyframes;
  stats_.map_points_loaded = contents.map_points;
  stats_.keyframe_depth_images_loaded = contents.images.size();
  spdlog::info(
      "{}: map loaded in {:.0f} ms: {} keyframes ({} with depth images), {} map points, {} dense "
      "scans{}",
      path, watch.elapsed_ms(), contents.keyframes, contents.images.size(), contents.map_points,
      contents.dense_scans.size(),
      contents.dense_scans.empty() || config_.dense.octomap_enabled ? "" : " (no octree: unused)");
  return contents;
}

void System::save_map(const std::string& path) const {
  map::MapFileInfo info;
  info.image_width = camera_.width;
  info.image_height = camera_.height;
  info.fx = camera_.fx;
  info.fy = camera_.fy;
  info.cx = camera_.cx;
  info.cy = camera_.cy;
  info.descriptor_tag = vocabulary_->descriptor_tag();
  info.vocabulary_words = vocabulary_->word_count();
  const Stopwatch watch;
  map::save_map_file(
      *map_, info, path, [this](map::KeyFrameId id) { return dynamic_->keyframe_images(id); },
      dense_->dense_scans());
  spdlog::info("{}: sparse map written in {:.0f} ms", path, watch.elapsed_ms());
}

FrameOutcome System::process(const io::RgbdFrame& input, std::optional<CnnMask> cnn) {
  if (finished_) throw Error("System::process called after finish()");
  rethrow_worker_error();
  if (config_.tracking.localization_only && !map_loaded_) {
    throw ConfigError::for_key("tracking.localization_only",
                               "needs a map loaded from a file (--load-map)");
  }
  Stopwatch frame_watch;

  FrameOutcome outcome;
  DynamicMasks& masks = outcome.masks;
  cv::Mat cnn_exclusion;
  if (dynamic_->enabled() && !cnn) cnn = dynamic_->cnn_mask(input);
  // The frame with its depth at the colour image's instant once the low-cost pose gives the
  // motion (remove_moving_features; a camera without depth_time_offset_s keeps it as read):
  // the multi-view checks, the keyframe's view, the memory and the dense map use it; tracking
  // uses the depth as read (aligning its keypoints' depth with the predicted motion did not
  // help it: docs/dynamics.md, "Depth in time").
  io::RgbdFrame frame = input;
  if (dynamic_->enabled()) {
    masks.cnn = std::move(cnn->mask);
    masks.segmentation_ms = cnn->elapsed_ms;
    if (cnn->turned) ++stats_.segmentations_turned;
    stats_.cnn_pictures_dropped += static_cast<std::size_t>(cnn->pictures_dropped);
    stats_.cnn_pictures_unjudged += static_cast<std::size_t>(cnn->pictures_unjudged);
    if (dynamic_->has_segmenter()) {
      timings_.record(cnn->reused ? "segmentation.reused_mask" : "segmentation",
                      masks.segmentation_ms);
    }
    cnn_exclusion = dynamic_->exclusion_mask(masks.cnn);
  }
  // A young map in threaded mode (fewer keyframes created since it began, or was reset, than
  // threaded_lockstep_keyframes): its keyframes are processed before the next frame is tracked.
  // The wait ends at once when the worker has exited.
  if (config_.mode == RunMode::kThreaded &&
      stats_.keyframes_created - keyframes_before_map_ <
          static_cast<std::size_t>(config_.threaded_lockstep_keyframes)) {
    Stopwatch wait;
    mapping_gate_.wait_until_idle();
    timings_.record("lockstep_wait", wait.elapsed_ms());
  }
  // ORB features once per frame, outside the CNN mask; the geometry check drops more of them.
  tracking::Frame current = tracker_->prepare_frame(input, cnn_exclusion);
  if (dynamic_->enabled()) {
    const cv::Mat geometry_exclusion = remove_moving_features(frame, current, masks);
    dynamic_->finish_masks(masks, frame.rgb, cnn_exclusion, geometry_exclusion);
    if (masks.refined) timings_.record("edge_refinement", masks.refinement_ms);
  }

  tracking::MappingStatus status;
  const bool threaded = config_.mode == RunMode::kThreaded;
  // Closed once the keyframe, if any, is queued: loop closing does not stop mapping in between,
  // and while it asks to stop, tracking creates no keyframe.
  InsertionWindow insertion(threaded ? &mapping_gate_ : nullptr);
  if (threaded) {
    status.stopped = !insertion.allowed();
    status.queued_keyframes = mapping_queue_->size();
    status.accepts_keyframes = mapping_gate_.mapping_idle();
  } else {
    status.accepts_keyframes = frames_since_keyframe_ >= config_.deterministic_mapping_busy_frames;
  }
  ++frames_since_keyframe_;
  tracking::TrackingResult& result = outcome.tracking;
  // The world frame the tracked pose is in, unless loop closing moves it meanwhile (then data
  // kept at that pose is not anchored, and the pose is not used as the previous one).
  const std::uint64_t frame_changes = map_->frame_change_count();
  result = tracker_->track(std::move(current), status);
  timings_.record("tracking", result.timings.total_ms);
  timings_.record("tracking.features", result.timings.features_ms);
  timings_.record("tracking.initial_pose", result.timings.initial_pose_ms);
  timings_.record("tracking.local_map", result.timings.local_map_ms);
  timings_.record("tracking.keyframe", result.timings.keyframe_ms);
  if (result.relocalized_at_once) {
    ++stats_.relocalizations_in_same_frame;
    if (dynamic_->enabled()) {
      // The geometry check and the memory looked at the prediction that failed (the low-cost
      // pose failed, so constant_velocity_pose()): their masks belong to another pose. The
      // frame's keyframe and the dense map get the CNN mask only (review, stop 29).
      masks.geometry.release();
      masks.memory.release();
      masks.free_space.release();
      masks.free_space_regions.release();
      masks.free_space_votes = {};
      dynamic_->finish_masks(masks, frame.rgb, cnn_exclusion, cv::Mat());
      if (masks.refined) timings_.record("edge_refinement", masks.refinement_ms);
    }
  }

  ++stats_.frames;
  stats_.free_space_regions_dropped +=
      static_cast<std::size_t>(masks.free_space_stats.regions_dropped);
  if (result.tracked()) {
    ++stats_.frames_tracked;
    const SE3 T_c_w = result.T_w_c->inverse();
    const std::optional<SE3> previous = previous_pose(frame_changes);
    // A relocalized frame may have jumped from the previous one (tracking failed on it and it
    // relocalized at once, tracking.relocalization.same_frame): no velocity across that.
    const bool relocalized = result.state == tracking::TrackingState::kRelocalized;
    velocity_ =
        previous && !relocalized ? std::optional<SE3>(T_c_w * previous->inverse()) : std::nullopt;
    last_pose_stamp_s_ = frame.timestamp_s;
    last_T_c_w_ = T_c_w;
    last_pose_frame_changes_ = frame_changes;
    last_reference_ = result.reference_keyframe;
    if (cnn && dynamic_->memory_enabled()) {
      if (const std::optional<SE3> T_new_old = memory_anchor_->correction()) {
        dynamic_->move_dynamic_surfaces(*T_new_old);
      }
      if (memory_anchor_->anchor(result.reference_keyframe, frame_changes)) {
        dynamic_->remember_cnn_mask(frame, *result.T_w_c, masks, cnn->reused);
      }
    }
  } else {
    last_T_c_w_.reset();
    velocity_.reset();
    if (result.state == tracking::TrackingState::kLost) ++stats_.frames_lost;
  }
  if (result.state == tracking::TrackingState::kRelocalized) ++stats_.relocalizations;
  if (result.motion_prior_used) ++stats_.frames_with_motion_prior;
  if (result.map_reset) {
    ++stats_.map_resets;
    keyframes_before_map_ = stats_.keyframes_created;  // the new map is young again
    // The map was cleared: nothing downstream may keep using the old keyframes. Local mapping
    // and loop closing forget their lists and drop keyframes made for the old map (still queued
    // in threaded mode): every keyframe created from now on has an id above the one reserved here.
    last_reference_.reset();
    dynamic_->forget_dynamic_surfaces();
    memory_anchor_->reset();
    const map::KeyFrameId first_valid_keyframe = map_->next_keyframe_id();
    // The old map's keyframes may live on a while (the dense stage holds them until it takes its
    // reset), in a world frame that is gone: they must not vote in the free-space check.
    dynamic_->forget_keyframes_before(first_valid_keyframe);
    mapper_->request_reset(first_valid_keyframe);
    loop_closer_->request_reset(first_valid_keyframe);
    dense_->reset();
  }

  if (config_.save_masks && !config_.output_dir.empty() && !outcome.masks.combined.empty()) {
    const auto dir = std::filesystem::path(config_.output_dir) / "masks";
    const std::string name = fmt::format("{:.6f}.png", frame.timestamp_s);
    saved_masks_.write_png(dir / name, outcome.masks.combined);
    // The parts, where they marked anything (an empty part is written as no file).
    const std::pair<const char*, const cv::Mat*> parts[] = {
        {"cnn", &outcome.masks.cnn},
        {"geometry", &outcome.masks.geometry},
        {"memory", &outcome.masks.memory},
        {"free_space", &outcome.masks.free_space}};
    for (const auto& [part, mask] : parts) {
      if (!mask->empty() && cv::countNonZero(*mask) > 0) {
        saved_masks_.write_png(dir / part / name, *mask);
      }
    }
  }

  if (result.new_keyframe) {
    ++stats_.keyframes_created;
    frames_since_keyframe_ = 0;
    if (threaded) {
      const bool queued = mapping_queue_->push(result.new_keyframe);
      insertion.close(queued);
      if (!queued) rethrow_worker_error();
    }
    dynamic_->remember_keyframe(result.new_keyframe, frame.depth_m, outcome.masks.combined,
                                outcome.masks.flagged);
    dense_->submit({result.new_keyframe, frame.rgb, frame.depth_m, outcome.masks.combined});
    if (!threaded) handle_keyframe_inline(result.new_keyframe);
  }
  insertion.close(false);
  timings_.record("frame_total", frame_watch.elapsed_ms());
  return outcome;
}

void System::record_local_mapping(double total_ms) {
  timings_.record("local_mapping", total_ms);
  const std::optional<mapping::LocalMapperTimings> stages = mapper_->statistics().last_timings;
  if (!stages) return;  // the keyframe belonged to a map that was reset
  const mapping::LocalMapperTimings& t = *stages;
  timings_.record("local_mapping.insertion", t.insertion_ms);
  timings_.record("local_mapping.point_culling", t.point_culling_ms);
  timings_.record("local_mapping.triangulation", t.triangulation_ms);
  // Stages that did not run for this keyframe are not samples of their cost.
  if (t.fusion_ms) timings_.record("local_mapping.fusion", *t.fusion_ms);
  if (t.local_ba_ms) timings_.record("local_mapping.local_ba", *t.local_ba_ms);
  if (t.keyframe_culling_ms)
    timings_.record("local_mapping.keyframe_culling", *t.keyframe_culling_ms);
}

void System::handle_keyframe_inline(const map::KeyFramePtr& keyframe) {
  Stopwatch watch;
  map::KeyFramePtr kept = mapper_->process(keyframe, nullptr);
  record_local_mapping(watch.elapsed_ms());
  if (!kept) return;
  watch.reset();
  loop_closer_->process(kept);
  timings_.record("loop_closing", watch.elapsed_ms());
}

void System::mapping_worker() {
  try {
    while (auto keyframe = mapping_queue_->pop()) {
      mapping_gate_.begin_keyframe();
      Stopwatch watch;
      map::KeyFramePtr kept = mapper_->process(*keyframe, mapping_gate_.abort_flag());
      record_local_mapping(watch.elapsed_ms());
      mapping_gate_.end_keyframe();
      if (kept && !loop_queue_->push(kept)) break;
    }
  } catch (...) {
    store_error(std::current_exception());
  }
  mapping_gate_.worker_exited();
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
  shutdown_workers(/*wait_for_global_ba=*/false);
  std::lock_guard lock(error_mutex_);
  if (worker_error_) std::rethrow_exception(worker_error_);
}

void System::shutdown_workers(bool wait_for_global_ba) {
  if (mapping_queue_) mapping_queue_->close();
  if (mapping_thread_.joinable()) mapping_thread_.join();
  if (loop_queue_) loop_queue_->close();
  if (loop_thread_.joinable()) loop_thread_.join();
  if (loop_closer_) {
    if (wait_for_global_ba) {
      loop_closer_->wait_for_global_ba();
    } else {
      loop_closer_->stop();
    }
  }
}

void System::finish(Finish how) {
  if (finished_) return;
  finished_ = true;
  // Every stage is shut down even when one fails (a background global BA that threw, an error of
  // the dense stage): the dense thread must not outlive finish() while the outputs are written.
  // The first error is rethrown.
  auto attempt = [this](auto&& step) {
    try {
      step();
    } catch (...) {
      store_error(std::current_exception());
    }
  };
  attempt([this, how] { shutdown_workers(/*wait_for_global_ba=*/how == Finish::kComplete); });
  attempt([this] { dense_->finish(); });
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

std::vector<std::string> System::frame_output_errors() const {
  std::vector<std::string> errors;
  for (const auto& error : {saved_masks_.error(), dense_->saved_images_error()}) {
    if (error) errors.push_back(*error);
  }
  return errors;
}

SystemStatistics System::statistics() const {
  SystemStatistics s = stats_;
  s.poses = tracker_->frames_tracked();  // the camera trajectory's poses
  s.keyframes = map_->keyframe_count();
  s.map_points = map_->map_point_count();
  s.loops_closed = loop_closer_->loops_closed();
  s.dense = dense_->stats();
  return s;
}

}  // namespace ddl::pipeline
