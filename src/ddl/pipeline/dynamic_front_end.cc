#include "ddl/pipeline/dynamic_front_end.h"

#include <spdlog/spdlog.h>

#include <cmath>

#include "ddl/core/error.h"
#include "ddl/core/timing.h"
#include "ddl/dynamics/mask_depth_trim.h"
#include "ddl/dynamics/mask_edge_refinement.h"
#include "ddl/dynamics/mask_fusion.h"
#include "ddl/dynamics/picture_veto.h"
#include "ddl/segmentation/upright.h"

namespace ddl::pipeline {
namespace {

/// The multi-view checks a configuration runs, for messages.
const char* multi_view_checks(const DynamicConfig& config) {
  if (config.free_space.enabled && config.use_geometry)
    return "free-space and sparse geometry checks";
  if (config.free_space.enabled) return "free-space check";
  if (config.use_geometry) return "sparse geometry check";
  return "none configured: no dynamic mask at all";
}

}  // namespace

void DynamicConfig::validate() const {
  if (feature_border_px < 0 || feature_border_px > 50) {
    throw ConfigError::for_key("dynamic.feature_border_px", "must be in 0..50");
  }
  if (segmentation_interval < 1 || segmentation_interval > 30) {
    throw ConfigError::for_key("dynamic.segmentation_interval", "must be in 1..30");
  }
  if (segmentation_reuse_dilation_px < 0 || segmentation_reuse_dilation_px > 50) {
    throw ConfigError::for_key("dynamic.segmentation_reuse_dilation_px", "must be in 0..50");
  }
  if (keyframe_depth_cache < 1) {
    throw ConfigError::for_key("dynamic.keyframe_depth_cache", "must be >= 1");
  }
  if (enabled && use_segmentation) segmentation.validate();
  if (enabled && use_geometry) geometry.validate();
  if (enabled && use_segmentation) memory.validate();
  if (enabled && free_space.enabled) free_space.validate();
  if (enabled && use_segmentation && depth_trim.enabled) depth_trim.validate();
  if (enabled && use_segmentation && picture_veto.enabled) picture_veto.validate();
  if (enabled && edge_refinement.enabled) edge_refinement.validate();
}

DynamicFrontEnd::DynamicFrontEnd(const DynamicConfig& config, const camera::PinholeCamera& camera,
                                 const std::string& shared_dir)
    : config_(config), camera_(camera), memory_(config.memory, camera) {
  if (!config_.enabled || !config_.use_segmentation) return;
  if (config_.segmentation.upright &&
      config_.segmentation.backend != segmentation::Backend::kOnnx) {
    spdlog::warn(
        "dynamic.segmentation.upright applies to the onnx backend only: the {} backend's masks "
        "are used as they are",
        config_.segmentation.backend == segmentation::Backend::kFolder ? "folder" : "none");
  }
  try {
    segmenter_ = segmentation::make_segmenter(config_.segmentation, shared_dir);
  } catch (const segmentation::ModelNotFoundError& e) {
    if (!config_.fallback_without_model) throw;
    spdlog::warn(
        "{}; running with the multi-view checks only ({}; set "
        "dynamic.segmentation.model_path or --shared-dir)",
        e.what(), multi_view_checks(config_));
  }
}

std::string DynamicFrontEnd::segmenter_description() const {
  return segmenter_ ? segmenter_->description() : "none";
}

std::optional<double> DynamicFrontEnd::upright_turn(const io::RgbdFrame& frame) const {
  const segmentation::SegmenterConfig& c = config_.segmentation;
  if (!c.upright || c.backend != segmentation::Backend::kOnnx || !frame.up_c) return std::nullopt;
  const std::optional<double> turn = segmentation::upright_turn_rad(*frame.up_c);
  if (!turn || std::abs(*turn) < c.upright_min_roll_deg * M_PI / 180.0) return std::nullopt;
  return turn;
}

CnnMask DynamicFrontEnd::cnn_mask(const io::RgbdFrame& frame) {
  CnnMask out;
  if (!segmenter_) return out;
  const Stopwatch watch;
  // The schedule depends only on the frame indices, so it is the same on every run.
  const bool folder = config_.segmentation.backend == segmentation::Backend::kFolder;
  const bool reuse =
      !folder && last_cnn_index_ && frame.index > *last_cnn_index_ &&
      frame.index - *last_cnn_index_ < static_cast<std::size_t>(config_.segmentation_interval);
  // last_cnn_mask_ never shares its buffer with a published mask, which goes on to tracking and
  // the dense thread: OpenCV's reference counts (inside libopencv_core) are invisible to
  // ThreadSanitizer, so a shared buffer freed here after they read it shows up as a race.
  // Both masks are cut to their regions' depth in this frame (the spill of the upsampled mask,
  // and of the growth of a reused one, onto the background behind a person).
  const auto trimmed = [&](const cv::Mat& mask) {
    return config_.depth_trim.enabled && !frame.depth_m.empty()
               ? dynamics::trim_mask_by_depth(mask, frame.depth_m, config_.depth_trim)
               : mask;
  };
  if (reuse) {
    out.mask = trimmed(
        dynamics::feature_exclusion_mask(last_cnn_mask_, config_.segmentation_reuse_dilation_px));
    if (out.mask.data == last_cnn_mask_.data) out.mask = last_cnn_mask_.clone();  // unchanged
    out.reused = true;
  } else {
    cv::Mat mask;
    const std::optional<double> turn = upright_turn(frame);
    if (turn) {
      mask =
          segmentation::segment_turned(*segmenter_, frame.rgb, frame.rgb_path, *turn).dynamic_mask;
      out.turned = true;
    } else {
      mask = segmenter_->segment(frame.rgb, frame.rgb_path).dynamic_mask;
    }
    if (folder && stored_mask_mapping_) mask = stored_mask_mapping_(mask);
    out.mask = trimmed(mask);
    // Pictures are judged once per mask the backend gives (the network's or a folder's); a
    // reused mask was judged when it was made.
    if (config_.picture_veto.enabled && !frame.depth_m.empty()) {
      dynamics::PictureVetoStats veto;
      out.mask = dynamics::drop_pictures(out.mask, frame.depth_m, config_.picture_veto, &veto,
                                         source_area_);
      out.pictures_dropped = veto.dropped;
      out.pictures_unjudged = veto.unjudged;
    }
    last_cnn_mask_ = out.mask.clone();
    last_cnn_index_ = frame.index;
  }
  out.elapsed_ms = watch.elapsed_ms();
  return out;
}

std::vector<dynamics::ReferenceView> DynamicFrontEnd::reference_views(
    const std::vector<map::KeyFramePtr>& references) const {
  std::vector<dynamics::ReferenceView> views;
  if (!config_.enabled || !config_.use_geometry) return views;
  for (const map::KeyFramePtr& kf : references) {
    if (static_cast<int>(views.size()) >= config_.geometry.max_reference_keyframes) break;
    dynamics::ReferenceView view;
    view.T_w_c = kf->T_w_c();
    const map::FrameFeatures& f = kf->features();
    for (std::size_t i = 0; i < f.size(); ++i) {
      if (!f.has_depth(i)) continue;
      view.pixels.push_back(f.keypoints[i].pt);
      view.depth_m.push_back(f.depth_m[i]);
    }
    {
      std::lock_guard lock(cache_mutex_);
      auto it = depth_cache_.find(kf->id());
      if (it != depth_cache_.end()) {
        view.depth_image_m = it->second.depth_m;
        view.dynamic_mask = it->second.dynamic_mask;
      }
    }
    views.push_back(std::move(view));
  }
  return views;
}

cv::Mat DynamicFrontEnd::geometry_mask(const io::RgbdFrame& frame, const SE3& T_c_w,
                                       const std::vector<dynamics::ReferenceView>& references,
                                       dynamics::GeometryCheckStats* stats,
                                       const std::optional<SE3>& T_c_w_previous) const {
  if (!config_.enabled || !config_.use_geometry || references.empty()) return {};
  return dynamics::geometry_dynamic_mask(frame.depth_m, T_c_w, references, camera_,
                                         config_.geometry, stats, T_c_w_previous);
}

std::vector<dynamics::FreeSpaceView> DynamicFrontEnd::free_space_views(const io::RgbdFrame& frame,
                                                                       const SE3& T_c_w) const {
  std::vector<dynamics::FreeSpaceView> views;
  if (!config_.enabled || !config_.free_space.enabled || frame.depth_m.empty()) return views;
  std::vector<SE3> poses;
  {
    std::lock_guard lock(cache_mutex_);
    // The cache is ordered by id, so oldest first, as the selection's spread needs.
    for (const auto& [id, images] : depth_cache_) {
      const map::KeyFramePtr kf = images.keyframe.lock();
      if (!kf || kf->is_bad() || images.free_space.packed_mm.empty()) continue;
      // The age rule holds within a session: a loaded map's keyframes saw the scene at another
      // time whatever their stamps say.
      if (!images.loaded &&
          frame.timestamp_s - kf->timestamp_s() < config_.free_space.min_reference_age_s) {
        continue;
      }
      views.push_back(images.free_space);
      poses.push_back(kf->T_w_c());
    }
  }
  const std::vector<std::size_t> chosen =
      dynamics::select_free_space_views(frame.depth_m, T_c_w, poses, camera_, config_.free_space);
  std::vector<dynamics::FreeSpaceView> out;
  out.reserve(chosen.size());
  for (const std::size_t k : chosen) {
    out.push_back(std::move(views[k]));
    out.back().T_w_c = poses[k];
  }
  return out;
}

cv::Mat DynamicFrontEnd::free_space_mask(const io::RgbdFrame& frame, const SE3& T_c_w,
                                         const std::vector<dynamics::FreeSpaceView>& views,
                                         dynamics::FreeSpaceVotes* votes,
                                         dynamics::FreeSpaceStats* stats, cv::Mat* ungrown) const {
  if (ungrown != nullptr) *ungrown = cv::Mat();
  if (!config_.enabled || !config_.free_space.enabled || views.empty()) return {};
  *votes = dynamics::free_space_votes(frame.depth_m, T_c_w, views, camera_, config_.free_space);
  if (stats != nullptr) stats->views = static_cast<int>(views.size());
  return dynamics::free_space_mask(frame.depth_m, *votes, config_.free_space, stats, ungrown);
}

cv::Mat DynamicFrontEnd::exclusion_mask(const cv::Mat& mask) const {
  return dynamics::feature_exclusion_mask(mask, config_.feature_border_px);
}

bool DynamicFrontEnd::memory_enabled() const {
  return config_.enabled && config_.use_segmentation && config_.memory.enabled && segmenter_;
}

cv::Mat DynamicFrontEnd::memory_mask(const io::RgbdFrame& frame, const SE3& T_c_w,
                                     dynamics::DynamicMemoryStats* stats) {
  if (!memory_enabled()) return {};
  return memory_.recall(frame.index, T_c_w, frame.depth_m, frame.rgb, stats);
}

void DynamicFrontEnd::remember_cnn_mask(const io::RgbdFrame& frame, const SE3& T_w_c,
                                        const DynamicMasks& masks, bool reused) {
  const cv::Mat& mask = config_.memory.remember_judged ? masks.cnn_kept : masks.cnn;
  if (!memory_enabled() || reused || mask.empty()) return;
  memory_.remember(frame.index, T_w_c, mask, frame.depth_m, frame.rgb);
}

void DynamicFrontEnd::finish_masks(DynamicMasks& masks, const cv::Mat& bgr,
                                   const cv::Mat& cnn_exclusion,
                                   const cv::Mat& moved_exclusion) const {
  // The sources' regions that the free-space votes saw as static surface are left out of the
  // combined mask; tracking has already dropped their features (the CNN's before the low-cost
  // pose that the votes need).
  const auto judged = [&](const cv::Mat& mask, bool judge) {
    return judge && !masks.free_space_votes.free_votes.empty()
               ? dynamics::drop_static_regions(mask, masks.free_space_votes, config_.free_space,
                                               &masks.free_space_stats)
               : mask;
  };
  const dynamics::FreeSpaceConfig& f = config_.free_space;
  masks.free_space_stats.regions_dropped = 0;  // of this call (a relocalized frame calls twice)
  masks.flagged = dynamics::combine_masks(dynamics::combine_masks(masks.cnn, masks.geometry),
                                          dynamics::combine_masks(masks.memory, masks.free_space));
  masks.cnn_kept = judged(masks.cnn, true);
  masks.combined = dynamics::combine_masks(
      dynamics::combine_masks(masks.cnn_kept, judged(masks.geometry, f.judge_geometry)),
      dynamics::combine_masks(judged(masks.memory, true), masks.free_space));
  masks.refined = false;
  masks.refinement_ms = 0.0;
  if (config_.edge_refinement.enabled && !masks.combined.empty() && !bgr.empty()) {
    const Stopwatch watch;
    const dynamics::EdgeRefinementConfig& refinement = config_.edge_refinement;
    masks.combined = dynamics::refine_mask_edges(
        masks.combined, bgr, refinement,
        refinement.keep_free_space_regions ? masks.free_space_regions : cv::Mat());
    masks.refinement_ms = watch.elapsed_ms();
    masks.refined = true;
  }
  masks.exclusion = dynamics::combine_masks(cnn_exclusion, moved_exclusion);
}

std::optional<map::KeyFrameImages> DynamicFrontEnd::keyframe_images(map::KeyFrameId id) const {
  std::lock_guard lock(cache_mutex_);
  const auto it = depth_cache_.find(id);
  if (it == depth_cache_.end()) return std::nullopt;
  return map::KeyFrameImages{it->second.depth_m, it->second.dynamic_mask};
}

void DynamicFrontEnd::remember_keyframe(const map::KeyFramePtr& keyframe, const cv::Mat& depth_m,
                                        const cv::Mat& dynamic_mask, const cv::Mat& flagged_mask) {
  keep_keyframe(keyframe, depth_m, dynamic_mask, flagged_mask, false);
}

void DynamicFrontEnd::remember_loaded_keyframe(const map::KeyFramePtr& keyframe,
                                               const cv::Mat& depth_m,
                                               const cv::Mat& dynamic_mask) {
  keep_keyframe(keyframe, depth_m, dynamic_mask, cv::Mat(), true);
}

void DynamicFrontEnd::forget_keyframes_before(map::KeyFrameId first_kept) {
  std::lock_guard lock(cache_mutex_);
  depth_cache_.erase(depth_cache_.begin(), depth_cache_.lower_bound(first_kept));
}

void DynamicFrontEnd::keep_keyframe(const map::KeyFramePtr& keyframe, const cv::Mat& depth_m,
                                    const cv::Mat& dynamic_mask, const cv::Mat& flagged_mask,
                                    bool loaded) {
  if (memory_enabled()) memory_.add_static_view(keyframe->T_w_c(), depth_m, dynamic_mask);
  if (!config_.keeps_keyframe_images()) return;
  // A mask that marked nothing is kept as none: the check reads an empty mask as unmasked.
  const bool any_dynamic = !dynamic_mask.empty() && cv::countNonZero(dynamic_mask) > 0;
  const cv::Mat kept_mask = any_dynamic ? dynamic_mask : cv::Mat();
  KeyframeImages images{keyframe, depth_m, kept_mask, {}, loaded};
  if (config_.free_space.enabled) {
    images.free_space = dynamics::prepare_free_space_view(
        SE3(), depth_m, flagged_mask.empty() ? kept_mask : flagged_mask, config_.free_space);
  }
  std::lock_guard lock(cache_mutex_);
  depth_cache_[keyframe->id()] = std::move(images);
  if (depth_cache_.size() <= config_.keyframe_depth_cache) return;
  // Culled keyframes leave first, then the oldest. Until stop 26 the oldest left first whatever
  // else was there, with a limit of 30: a camera back in a place mapped more than 30 keyframes
  // before had references without depth, and the check tested nothing (review; syn_static_loop,
  // frames 914-1000).
  for (auto it = depth_cache_.begin(); it != depth_cache_.end();) {
    const map::KeyFramePtr kf = it->second.keyframe.lock();
    it = (!kf || kf->is_bad()) ? depth_cache_.erase(it) : std::next(it);
  }
  while (depth_cache_.size() > config_.keyframe_depth_cache)
    depth_cache_.erase(depth_cache_.begin());
}

}  // namespace ddl::pipeline
