#include "ddl/tracking/tracker.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>

#include "ddl/core/error.h"
#include "ddl/core/timing.h"
#include "ddl/tracking/keyframe_creation.h"
#include "ddl/tracking/keyframe_decision.h"

namespace ddl::tracking {
namespace {

const TrackerConfig& validated(const TrackerConfig& config) {
  config.validate();
  return config;
}

template <typename T>
std::shared_ptr<T> require_non_null(std::shared_ptr<T> p, const char* what) {
  if (!p) throw Error(std::string("Tracker: ") + what + " must not be null");
  return p;
}

}  // namespace

std::string_view to_string(TrackingState state) {
  switch (state) {
    case TrackingState::kNotInitialized:
      return "not_initialized";
    case TrackingState::kOk:
      return "ok";
    case TrackingState::kLost:
      return "lost";
    case TrackingState::kRelocalized:
      return "relocalized";
  }
  return "unknown";
}

std::string_view to_string(TrackingMethod method) {
  switch (method) {
    case TrackingMethod::kNone:
      return "none";
    case TrackingMethod::kInitialization:
      return "initialization";
    case TrackingMethod::kMotionModel:
      return "motion_model";
    case TrackingMethod::kReferenceKeyFrame:
      return "reference_keyframe";
    case TrackingMethod::kRelocalization:
      return "relocalization";
  }
  return "unknown";
}

Tracker::Tracker(const TrackerConfig& config, const camera::PinholeCamera& camera,
                 std::shared_ptr<map::Map> map,
                 std::shared_ptr<const vocabulary::Vocabulary> vocabulary,
                 std::shared_ptr<vocabulary::BowDatabase> keyframe_database)
    : config_(validated(config)),
      map_(require_non_null(std::move(map), "map")),
      vocabulary_(require_non_null(std::move(vocabulary), "vocabulary")),
      database_(std::move(keyframe_database)),
      builder_(camera, config_.orb, config_.frame),
      estimator_(*builder_.geometry(), config_.optimizer),
      local_map_(config_.matching),
      relocalizer_(config_.relocalization, config_.frame.bow_levels_up, map_, vocabulary_,
                   database_) {
  // A vocabulary trained on descriptors of another BRIEF pattern gives meaningless words.
  const features::BriefPattern& pattern = builder_.brief_pattern();
  const std::uint64_t tag = vocabulary::descriptor_fingerprint(pattern.data(), sizeof(pattern));
  if (vocabulary_->descriptor_tag() != 0 && vocabulary_->descriptor_tag() != tag) {
    throw Error(fmt::format(
        "the vocabulary was trained for another ORB descriptor (BRIEF pattern tag {:016x}, this "
        "build's extractor has {:016x}): train one with `ddl_slam vocab train` or use the one "
        "shipped in vocab/",
        vocabulary_->descriptor_tag(), tag));
  }
  // An idf vocabulary trained on one image weighs every word 0 (log(1 / 1)): every bag of words
  // is empty, and relocalization and loop detection would silently find nothing (review, stop 26).
  bool any_weight = false;
  for (vocabulary::WordId w = 0; w < vocabulary_->word_count() && !any_weight; ++w) {
    any_weight = vocabulary_->word_weight(w) > 0.0;
  }
  if (!any_weight) {
    throw Error(
        "every word of the vocabulary weighs 0 (an idf vocabulary trained on a single image?): "
        "bags of words would be empty and relocalization and loop closing would find nothing; "
        "train one on more images with `ddl_slam vocab train` or use the one shipped in vocab/");
  }
  // ORB-SLAM2's direct index sits at depth 2 (levels_up 4 of its 6 levels); the default suits the
  // shipped 5-level vocabulary. Another depth works, with fewer or less selective BoW matches.
  if (const int depth = vocabulary_->levels() - config_.frame.bow_levels_up; depth != 2) {
    spdlog::warn(
        "tracking.frame.bow_levels_up {} puts the direct index at depth {} of this {}-level "
        "vocabulary; depth 2 (bow_levels_up {}) is what ORB-SLAM2 uses and the defaults assume",
        config_.frame.bow_levels_up, std::max(0, depth), vocabulary_->levels(),
        std::max(0, vocabulary_->levels() - 2));
  }
}

Frame Tracker::prepare_frame(const io::RgbdFrame& frame, const cv::Mat& dynamic_mask) {
  const Stopwatch watch;
  Frame prepared = builder_.build(frame, dynamic_mask, next_frame_id_++);
  prepared_ = PreparedFrame{};
  motion_prior_.reset();  // set only by motion-model tracking of this frame
  prepared_.frame_id = prepared.id();
  prepared_.frame_index = frame.index;
  prepared_.features_ms = watch.elapsed_ms();
  return prepared;
}

std::optional<SE3> Tracker::low_cost_pose(Frame& frame) {
  if (frame.id() != prepared_.frame_id || prepared_.initial_pose_done) {
    throw Error("Tracker::low_cost_pose: call it once, on the frame prepare_frame() returned last");
  }
  const TrackingState state = state_.load();
  if (state == TrackingState::kNotInitialized || state == TrackingState::kLost) return std::nullopt;
  const Stopwatch watch;
  map_->read_consistent([&] {
    prepared_.frame_changes = map_->frame_change_count();
    prepared_.initial_pose_ok = estimate_initial_pose(frame, prepared_.method);
  });
  prepared_.initial_pose_done = true;
  prepared_.initial_pose_ms = watch.elapsed_ms();
  if (!prepared_.initial_pose_ok) return std::nullopt;
  return frame.T_c_w();
}

std::size_t Tracker::exclude_features(Frame& frame, const cv::Mat& mask) {
  const Stopwatch watch;
  const int matched_before = frame.matched_count();
  const std::size_t dropped = frame.drop_features_in(mask);
  if (prepared_.initial_pose_ok && frame.id() == prepared_.frame_id &&
      frame.matched_count() < matched_before) {
    // The low-cost pose saw the dropped matches: estimate it again from the static ones.
    map_->read_consistent([&] {
      optimize_pose(frame);
      prepared_.initial_pose_ok = discard_outliers(frame) >= config_.matching.min_map_matches;
    });
    if (!prepared_.initial_pose_ok) {
      // Too little left: track() estimates the initial pose again with all its fallbacks.
      frame.clear_map_points();
      frame.clear_rejected_points();  // rejected against the discarded pose
      prepared_.initial_pose_done = false;
    }
  }
  prepared_.initial_pose_ms += watch.elapsed_ms();
  return dropped;
}

TrackingResult Tracker::track(Frame frame, const MappingStatus& mapping) {
  const Stopwatch total;
  if (frame.id() != prepared_.frame_id || !frame.valid()) {
    throw Error("Tracker::track: the frame must be the one prepare_frame() returned last");
  }
  TrackingResult result;
  result.frame_index = prepared_.frame_index;
  result.timestamp_s = frame.timestamp_s();
  result.timings.features_ms = prepared_.features_ms;
  result.num_features = frame.size();

  const map::FrameFeatures& features = frame.features();
  result.keypoints.resize(frame.size());
  for (std::size_t i = 0; i < frame.size(); ++i) {
    result.keypoints[i].u = features.keypoints[i].pt.x;
    result.keypoints[i].v = features.keypoints[i].pt.y;
  }
  // track_locked() sets the matched flags of a tracked frame.
  map_->read_consistent([&] { track_locked(frame, mapping, result); });
  last_frame_ = std::move(frame);
  // The whole tracking work of the frame, also what prepare_frame() and low_cost_pose() did.
  result.timings.total_ms = total.elapsed_ms() + prepared_.features_ms +
                            (prepared_.initial_pose_done ? prepared_.initial_pose_ms : 0.0);
  return result;
}

TrackingResult Tracker::track(const io::RgbdFrame& frame, const cv::Mat& dynamic_mask,
                              const MappingStatus& mapping) {
  return track(prepare_frame(frame, dynamic_mask), mapping);
}

void Tracker::track_locked(Frame& frame, const MappingStatus& mapping, TrackingResult& result) {
  Stopwatch stage;
  if (state_.load() == TrackingState::kNotInitialized) {
    const bool ok = initialize(frame, result);
    result.timings.initial_pose_ms = stage.elapsed_ms();
    if (ok) {
      state_ = TrackingState::kOk;
      result.state = TrackingState::kOk;
      result.method = TrackingMethod::kInitialization;
      result.T_w_c = frame.T_w_c();
      result.reference_keyframe = frame.reference_keyframe();
      result.num_inliers = frame.matched_count();
      trajectory_.add_tracked(frame.timestamp_s(), frame.T_c_w(), frame.reference_keyframe());
      last_T_c_r_ = SE3();
      last_frame_tracked_ = true;
    } else {
      result.state = TrackingState::kNotInitialized;
      trajectory_.add_lost(frame.timestamp_s());
      last_frame_tracked_ = false;
    }
    return;
  }

  bool ok = false;
  const bool was_lost = state_.load() == TrackingState::kLost;
  if (prepared_.initial_pose_done && map_->frame_change_count() != prepared_.frame_changes) {
    // Loop closing moved the map since low_cost_pose() (threaded mode): that pose, and the last
    // frame it was predicted from, are in the old world frame. Estimate it again, as ORB-SLAM2
    // does under one map-update lock from the initial pose to the local map (found by review).
    // A local BA in between does not count: it refines the map in place (review, stop 25: it
    // made every frame after a keyframe's local BA estimate its initial pose twice).
    ++low_cost_poses_redone_;
    frame.clear_map_points();
    frame.clear_rejected_points();  // rejected against the discarded pose
    prepared_.initial_pose_done = false;
  }
  if (prepared_.initial_pose_done) {
    // low_cost_pose() ran this step already (only while tracking was ok).
    ok = prepared_.initial_pose_ok;
    result.method = prepared_.method;
    result.timings.initial_pose_ms = prepared_.initial_pose_ms;
  } else {
    if (!was_lost) {
      ok = estimate_initial_pose(frame, result.method);
    } else {
      result.method = TrackingMethod::kRelocalization;
      ok = relocalize(frame);
    }
    result.timings.initial_pose_ms = stage.elapsed_ms();
  }

  frame.set_reference_keyframe(reference_keyframe_);
  if (ok) {
    stage.reset();
    ok = track_local_map(frame, result.timings);
    result.timings.local_map_ms = stage.elapsed_ms();
  }
  bool relocalized_at_once = false;
  if (!ok && !was_lost && config_.relocalization.same_frame) {
    // Tracking failed on this frame (a jump after dropped frames, the view swept away): the
    // frame tries relocalization itself instead of being lost, as ORB-SLAM2 leaves it to the next
    // frame. Nothing of the failed attempt is kept: its matches, its rejected points and a
    // motion prior whose prediction did not hold.
    motion_prior_.reset();
    frame.clear_map_points();
    frame.clear_rejected_points();
    stage.reset();
    relocalized_at_once = relocalize(frame);
    result.timings.initial_pose_ms += stage.elapsed_ms();
    if (relocalized_at_once) {
      result.method = TrackingMethod::kRelocalization;
      frame.set_reference_keyframe(reference_keyframe_);
      stage.reset();
      TrackingTimings local_map_timings;
      relocalized_at_once = track_local_map(frame, local_map_timings);
      result.timings.local_map_ms += stage.elapsed_ms();
      result.timings.local_map_update_ms += local_map_timings.local_map_update_ms;
      result.timings.local_map_search_ms += local_map_timings.local_map_search_ms;
      result.timings.local_map_pose_ms += local_map_timings.local_map_pose_ms;
    }
    ok = relocalized_at_once;
  }

  if (!ok) {
    state_ = TrackingState::kLost;
    result.state = TrackingState::kLost;
    result.method = TrackingMethod::kNone;
    motion_model_.reset();
    last_frame_tracked_ = false;
    trajectory_.add_lost(frame.timestamp_s());
    if (!was_lost) spdlog::info("tracking lost at frame {}", result.frame_index);
    if (!map_loaded_ && config_.reset_when_lost_max_keyframes >= 0 &&
        map_->keyframe_count() <= static_cast<std::size_t>(config_.reset_when_lost_max_keyframes)) {
      reset(result);
    }
    return;
  }

  const bool relocalized = was_lost || relocalized_at_once;
  const TrackingState state = relocalized ? TrackingState::kRelocalized : TrackingState::kOk;
  if (was_lost) spdlog::info("relocalized at frame {}", result.frame_index);
  if (relocalized_at_once) {
    spdlog::info("tracking failed at frame {}, relocalized in the same frame", result.frame_index);
  }
  result.relocalized_at_once = relocalized_at_once;
  state_ = state;
  result.state = state;
  result.motion_prior_used = motion_prior_.has_value();
  // After a relocalization in the same frame this learns the jump, but the model is not used on
  // the next frame (no motion model within 2 frames of a relocalization), which replaces it.
  if (last_frame_tracked_ && last_frame_.has_pose()) {
    motion_model_.update(frame.T_c_w(), last_frame_.T_c_w(),
                         frame.timestamp_s() - last_frame_.timestamp_s());
  } else {
    motion_model_.reset();
  }
  // Matches to points nobody observes (none are made in SLAM mode, but fusion may leave some)
  // do not go into keyframes.
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const map::MapPointPtr& p = frame.map_point(i);
    if (p && p->num_observations() < 1) frame.clear_map_point(i);
  }

  // The inlier matches, before a new keyframe gives the frame its new close points (as
  // ORB-SLAM2's FrameDrawer::Update runs before keyframe insertion).
  for (std::size_t i = 0; i < frame.size(); ++i) {
    result.keypoints[i].matched = frame.map_point(i) != nullptr && !frame.is_outlier(i);
  }

  stage.reset();
  maybe_create_keyframe(frame, mapping, result);
  result.timings.keyframe_ms = stage.elapsed_ms();

  // Outliers went into the keyframe (local BA decides about them) but the next frame must not
  // be predicted from them.
  for (std::size_t i = 0; i < frame.size(); ++i) {
    if (frame.map_point(i) && frame.is_outlier(i)) frame.clear_map_point(i);
  }

  result.T_w_c = frame.T_w_c();
  result.num_inliers = local_map_inliers_;
  result.reference_keyframe = frame.reference_keyframe();
  trajectory_.add_tracked(frame.timestamp_s(), frame.T_c_w(), frame.reference_keyframe());
  last_T_c_r_ = frame.T_c_w() * frame.reference_keyframe()->T_w_c();
  last_frame_tracked_ = true;
}

bool Tracker::estimate_initial_pose(Frame& frame, TrackingMethod& method) {
  refresh_last_frame();
  if (motion_model_.valid() && frame.id() >= last_relocalization_frame_id_ + 2) {
    method = TrackingMethod::kMotionModel;
    if (track_motion_model(frame)) return true;
  }
  method = TrackingMethod::kReferenceKeyFrame;
  return track_reference_keyframe(frame);
}

bool Tracker::initialize(Frame& frame, TrackingResult& result) {
  if (frame.size() <= static_cast<std::size_t>(config_.init_min_features)) return false;
  // Only keypoints with depth become map points: a frame without depth (a dropout, the sensor
  // covered) would start an empty map that the next frame cannot track, and a reset.
  std::size_t with_depth = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) with_depth += frame.has_depth(i) ? 1 : 0;
  if (with_depth < static_cast<std::size_t>(config_.init_min_depth_features)) return false;
  frame.set_T_c_w(SE3());
  map::KeyFramePtr keyframe =
      create_initial_keyframe(frame, *map_, *vocabulary_, config_.frame.bow_levels_up);
  reference_keyframe_ = keyframe;
  last_keyframe_frame_id_ = frame.id();
  local_map_.clear();
  motion_model_.reset();
  result.new_keyframe = keyframe;
  spdlog::info("map initialized at frame {} with {} points", result.frame_index,
               frame.matched_count());
  return true;
}

void Tracker::refresh_last_frame() {
  if (!last_frame_tracked_ || !last_frame_.valid()) return;
  for (std::size_t i = 0; i < last_frame_.size(); ++i) {
    const map::MapPointPtr& p = last_frame_.map_point(i);
    if (!p) continue;
    if (map::MapPointPtr replacement = p->replaced_by()) {
      last_frame_.set_map_point(i, std::move(replacement));
    }
  }
  if (const map::KeyFramePtr& reference = last_frame_.reference_keyframe()) {
    last_frame_.set_T_c_w(resolve_relative_pose(last_T_c_r_, reference));
  }
}

bool Tracker::track_reference_keyframe(Frame& frame) {
  motion_prior_.reset();  // set by a motion-model attempt that failed
  if (!reference_keyframe_ || !last_frame_.has_pose()) return false;
  frame.compute_bow(*vocabulary_, config_.frame.bow_levels_up);
  std::vector<map::MapPointPtr> matches;
  const int count = matcher_.match_bow(*reference_keyframe_, frame,
                                       config_.matching.reference_bow_ratio, matches);
  if (count < config_.matching.reference_min_matches) return false;
  frame.set_map_points(std::move(matches));
  frame.set_T_c_w(last_frame_.T_c_w());
  estimator_.optimize(frame);
  return discard_outliers(frame) >= config_.matching.min_map_matches;
}

bool Tracker::track_motion_model(Frame& frame) {
  const double elapsed_s = frame.timestamp_s() - last_frame_.timestamp_s();
  frame.set_T_c_w(motion_model_.predict(last_frame_.T_c_w(), elapsed_s));
  if (config_.motion_prior.enabled) {
    motion_prior_ = motion_model_.prior(frame.T_c_w(), elapsed_s, config_.motion_prior);
  }
  frame.clear_map_points();
  const float radius = config_.matching.motion_search_radius_px;
  int count = matcher_.match_last_frame(frame, last_frame_, radius);
  if (count < config_.matching.motion_min_matches) {
    frame.clear_map_points();
    count = matcher_.match_last_frame(frame, last_frame_, 2.0f * radius);
  }
  if (count < config_.matching.motion_min_matches) return false;
  optimize_pose(frame);
  return discard_outliers(frame) >= config_.matching.min_map_matches;
}

bool Tracker::track_local_map(Frame& frame, TrackingTimings& timings) {
  Stopwatch watch;
  if (map::KeyFramePtr reference = local_map_.update(frame))
    reference_keyframe_ = std::move(reference);
  frame.set_reference_keyframe(reference_keyframe_);
  timings.local_map_update_ms = watch.elapsed_ms();
  watch.reset();
  const bool just_relocalized = frame.id() < last_relocalization_frame_id_ + 2;
  const float radius = just_relocalized ? config_.matching.local_search_radius_after_relocalization
                                        : config_.matching.local_search_radius;
  const int matched_before = frame.matched_count();
  const int added = local_map_.search(frame, radius, matcher_);
  timings.local_map_search_ms = watch.elapsed_ms();
  watch.reset();
  optimize_pose(frame);
  timings.local_map_pose_ms = watch.elapsed_ms();

  int inliers = 0;
  for (std::size_t i = 0; i < frame.size(); ++i) {
    const map::MapPointPtr& p = frame.map_point(i);
    if (!p || frame.is_outlier(i)) continue;
    p->increase_found();
    if (p->num_observations() > 0) ++inliers;
  }
  local_map_inliers_ = inliers;
  spdlog::debug(
      "frame {}: {} matches before the local map ({} keyframes, {} points, {} in view), {} added, "
      "{} inliers",
      frame.id(), matched_before, local_map_.keyframes().size(), local_map_.points().size(),
      local_map_.projected_count(), added, inliers);
  const auto max_frames = static_cast<FrameId>(config_.keyframes.max_frames);
  if (frame.id() < last_relocalization_frame_id_ + max_frames &&
      inliers < config_.matching.local_map_min_inliers_after_relocalization) {
    return false;
  }
  return inliers >= config_.matching.local_map_min_inliers;
}

int Tracker::optimize_pose(Frame& frame) {
  return motion_prior_ ? estimator_.optimize_with_prior(frame, *motion_prior_)
                       : estimator_.optimize(frame);
}

bool Tracker::relocalize(Frame& frame) {
  const RelocalizationResult r = relocalizer_.relocalize(frame, matcher_, estimator_);
  if (!r.success) return false;
  last_relocalization_frame_id_ = frame.id();
  return true;
}

void Tracker::maybe_create_keyframe(Frame& frame, const MappingStatus& mapping,
                                    TrackingResult& result) {
  if (!reference_keyframe_ || config_.localization_only) return;
  KeyFrameContext context;
  context.frame_id = frame.id();
  context.last_keyframe_frame_id = last_keyframe_frame_id_;
  context.last_relocalization_frame_id = last_relocalization_frame_id_;
  context.keyframes_in_map = map_->keyframe_count();
  const int min_observations = min_observations_for(context.keyframes_in_map);
  context.reference_tracked_points = reference_keyframe_->tracked_map_points(min_observations);
  context.inliers = local_map_inliers_;
  context.close = count_close_points(frame);
  context.mapping = mapping;
  const bool insert = need_new_keyframe(config_.keyframes, context);
  spdlog::debug(
      "frame {}: keyframe {} (map {} keyframes, reference {} with {} points, {} inliers, close "
      "tracked {} ({} of >= 2 keyframes) / untracked {}, mapping {})",
      frame.id(), insert ? "inserted" : "not needed", context.keyframes_in_map,
      reference_keyframe_->id(), context.reference_tracked_points, context.inliers,
      context.close.tracked, context.close.tracked_established, context.close.non_tracked,
      mapping.accepts_keyframes ? "idle" : "busy");
  if (!insert) return;

  map::KeyFramePtr keyframe =
      create_keyframe(frame, *map_, config_.keyframes, *vocabulary_, config_.frame.bow_levels_up);
  reference_keyframe_ = keyframe;
  last_keyframe_frame_id_ = frame.id();
  result.new_keyframe = std::move(keyframe);
}

void Tracker::reset(TrackingResult& result) {
  spdlog::warn("tracking lost with {} keyframe(s) in the map: resetting the map",
               map_->keyframe_count());
  const map::KeyFrameId floor = map_->clear();
  if (database_) database_->clear(floor);
  local_map_.clear();
  motion_model_.reset();
  reference_keyframe_.reset();
  // A relocalization of the old map (one whose local map then failed) must not hold the new
  // map to the stricter inlier count after a relocalization (review, stop 29).
  last_relocalization_frame_id_ = 0;
  trajectory_.clear();
  last_frame_tracked_ = false;
  state_ = TrackingState::kNotInitialized;
  result.map_reset = true;
}

void Tracker::start_in_loaded_map() {
  if (next_frame_id_ != 0) {
    throw Error("Tracker::start_in_loaded_map: call it before the first frame");
  }
  if (map_->keyframe_count() == 0) {
    throw Error("Tracker::start_in_loaded_map: the map is empty");
  }
  map_loaded_ = true;
  state_ = TrackingState::kLost;
}

io::Trajectory Tracker::camera_trajectory() const {
  io::Trajectory trajectory;
  map_->read_consistent([&] { trajectory = trajectory_.camera_trajectory(); });
  return trajectory;
}

}  // namespace ddl::tracking
