#include "ddl/mapping/local_mapper.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <map>
#include <set>

#include "ddl/core/error.h"
#include "ddl/core/timing.h"
#include "ddl/mapping/keyframe_culling.h"
#include "ddl/mapping/keyframe_matching.h"
#include "ddl/mapping/triangulation.h"

namespace ddl::mapping {
namespace {

bool raised(const std::atomic<bool>* flag) {
  return flag != nullptr && flag->load(std::memory_order_acquire);
}

}  // namespace

LocalMapper::LocalMapper(const LocalMapperConfig& config, const camera::PinholeCamera& camera,
                         std::shared_ptr<map::Map> map,
                         std::shared_ptr<const vocabulary::Vocabulary> vocabulary,
                         std::shared_ptr<vocabulary::BowDatabase> keyframe_database)
    : config_(config),
      camera_(make_intrinsics(camera, config.bf)),
      close_depth_m_(config.close_depth_baselines * config.bf / camera.fx),
      map_(std::move(map)),
      vocabulary_(std::move(vocabulary)),
      database_(std::move(keyframe_database)),
      recent_points_(config.point_culling) {
  config_.validate();
  if (!map_ || !vocabulary_ || !database_) {
    throw Error("LocalMapper: map, vocabulary and keyframe database are required");
  }
}

void LocalMapper::request_reset(map::KeyFrameId first_valid_keyframe) {
  std::lock_guard lock(reset_mutex_);
  pending_reset_ = first_valid_keyframe;
}

void LocalMapper::apply_pending_reset() {
  std::optional<map::KeyFrameId> reset;
  {
    std::lock_guard lock(reset_mutex_);
    std::swap(reset, pending_reset_);
  }
  if (!reset) return;
  recent_points_.clear();
  first_valid_keyframe_ = std::max(first_valid_keyframe_, *reset);
}

bool LocalMapper::insert_keyframe(const map::KeyFramePtr& keyframe) {
  keyframe->compute_bow(*vocabulary_, config_.bow_levels_up);
  // Points tracked by the frame become observations of the keyframe; points the tracker created
  // for this keyframe (already observing it) go on probation (ORB-SLAM2 ProcessNewKeyFrame).
  const map::FrameFeatures& features = keyframe->features();
  const std::vector<map::MapPointPtr> points = keyframe->map_points();
  std::set<map::MapPointId> held;  // points the keyframe's features hold
  for (const map::MapPointPtr& point : points) {
    if (point && !point->is_bad()) held.insert(point->id());
  }
  for (std::size_t i = 0; i < points.size(); ++i) {
    map::MapPointPtr point = points[i];
    if (point && point->is_bad()) {
      // Fused or culled while the keyframe waited in the queue (threaded mode): the feature
      // follows the point that replaced it, or is freed for triangulation, which skips features
      // that hold a point (review, stop 25).
      point = point->replaced_by();
      for (int hop = 0; hop < 8 && point && point->is_bad(); ++hop) point = point->replaced_by();
      if (point && (point->is_bad() || !held.insert(point->id()).second)) {
        point = nullptr;  // gone too, or held by another feature already
      }
      if (point) {
        keyframe->set_map_point(i, point);
      } else {
        keyframe->erase_map_point(i);
      }
    }
    if (!point) continue;
    if (!point->is_in(keyframe->id())) {
      point->add_observation(keyframe, i, has_stereo(features, i));
      point->update_normal_and_depth();
      point->compute_distinctive_descriptor();
    } else {
      recent_points_.add(point);
    }
  }
  keyframe->update_connections();
  // Refused when tracking reset the map since this keyframe passed the check in process(): it
  // belongs to the old map (Map::clear).
  if (!map_->add_keyframe(keyframe)) return false;
  database_->add(keyframe->id(), keyframe->bow());
  return true;
}

int LocalMapper::fuse_with_neighbours(const map::KeyFramePtr& keyframe) {
  // Targets: the best covisibles and their best covisibles (ORB-SLAM2 SearchInNeighbors).
  std::map<map::KeyFrameId, map::KeyFramePtr> targets;
  for (const map::KeyFramePtr& kf :
       keyframe->best_covisibles(static_cast<std::size_t>(config_.fusion.neighbours))) {
    if (kf->is_bad() || kf->id() == keyframe->id()) continue;
    targets.emplace(kf->id(), kf);
  }
  std::vector<map::KeyFramePtr> first_ring;
  for (const auto& [id, kf] : targets) first_ring.push_back(kf);
  for (const map::KeyFramePtr& kf : first_ring) {
    for (const map::KeyFramePtr& kf2 :
         kf->best_covisibles(static_cast<std::size_t>(config_.fusion.second_neighbours))) {
      if (kf2->is_bad() || kf2->id() == keyframe->id()) continue;
      targets.emplace(kf2->id(), kf2);
    }
  }

  FuseParams params;
  params.radius_factor = config_.fusion.radius_factor;
  params.max_hamming = config_.fusion.max_hamming;
  params.chi2_mono = config_.fusion.chi2_mono;
  params.chi2_stereo = config_.fusion.chi2_stereo;
  params.min_view_cos = config_.fusion.min_view_cos;
  params.conflict = FuseConflict::kKeepMostObserved;

  int fused = 0;
  // The new keyframe's points into every target...
  for (const auto& [id, target] : targets) {
    const std::vector<map::MapPointPtr> points = keyframe->map_point_set();
    fused += fuse(target, target->T_c_w(), points, camera_, params, *map_);
  }
  // ... and the targets' points into the new keyframe.
  std::map<map::MapPointId, map::MapPointPtr> candidates;
  for (const auto& [id, target] : targets) {
    for (map::MapPointPtr& p : target->map_point_set()) candidates.emplace(p->id(), std::move(p));
  }
  std::vector<map::MapPointPtr> candidate_list;
  candidate_list.reserve(candidates.size());
  for (auto& [id, p] : candidates) candidate_list.push_back(std::move(p));
  fused += fuse(keyframe, keyframe->T_c_w(), candidate_list, camera_, params, *map_);

  for (const map::MapPointPtr& point : keyframe->map_point_set()) {
    point->compute_distinctive_descriptor();
    point->update_normal_and_depth();
  }
  keyframe->update_connections();
  return fused;
}

map::KeyFramePtr LocalMapper::process(const map::KeyFramePtr& keyframe,
                                      const std::atomic<bool>* abort) {
  apply_pending_reset();
  {
    std::lock_guard lock(stats_mutex_);
    stats_.last_timings.reset();
  }
  if (!keyframe || keyframe->id() < first_valid_keyframe_) return nullptr;
  LocalMapperTimings timings;
  Stopwatch watch;
  if (!insert_keyframe(keyframe)) {
    spdlog::debug("local mapping: keyframe {} belongs to a map that was reset", keyframe->id());
    return nullptr;
  }
  timings.insertion_ms = watch.elapsed_ms();

  watch.reset();
  const int culled_points = recent_points_.cull(keyframe->id(), *map_);
  timings.point_culling_ms = watch.elapsed_ms();

  watch.reset();
  const NewPointsResult created =
      create_new_map_points(keyframe, *map_, camera_, config_.triangulation, abort);
  for (const map::MapPointPtr& p : created.created) recent_points_.add(p);
  timings.triangulation_ms = watch.elapsed_ms();

  int fused = 0;
  if (!raised(abort)) {
    watch.reset();
    fused = fuse_with_neighbours(keyframe);
    timings.fusion_ms = watch.elapsed_ms();
  }

  LocalBaStatistics ba;
  std::vector<map::KeyFrameId> culled_keyframes;
  if (!raised(abort)) {
    watch.reset();
    if (config_.local_ba &&
        map_->keyframe_count() >= static_cast<std::size_t>(config_.local_ba_min_keyframes)) {
      ba = run_local_bundle_adjustment(keyframe, *map_, camera_, config_.optimizer, abort,
                                       static_cast<std::size_t>(config_.local_ba_max_keyframes));
    }
    if (ba.ran && !ba.aborted) timings.local_ba_ms = watch.elapsed_ms();
    watch.reset();
    culled_keyframes = cull_redundant_keyframes(keyframe, *map_, *database_, close_depth_m_,
                                                config_.keyframe_culling);
    timings.keyframe_culling_ms = watch.elapsed_ms();
  }

  spdlog::debug(
      "local mapping: keyframe {}: {} points culled, {} created, {} fused, local BA {} "
      "({} free / {} fixed keyframes, {} points, {} outliers{}), {} keyframes culled; "
      "ms: insert {:.1f}, cull {:.1f}, triangulate {:.1f}, fuse {:.1f}, BA {:.1f}, "
      "keyframe culling {:.1f}",
      keyframe->id(), culled_points, created.created.size(), fused, ba.ran ? "ran" : "skipped",
      ba.free_keyframes, ba.fixed_keyframes, ba.points, ba.outliers_erased,
      ba.aborted ? ", aborted" : "", culled_keyframes.size(), timings.insertion_ms,
      timings.point_culling_ms, timings.triangulation_ms, timings.fusion_ms.value_or(0.0),
      timings.local_ba_ms.value_or(0.0), timings.keyframe_culling_ms.value_or(0.0));
  {
    std::lock_guard lock(stats_mutex_);
    ++stats_.keyframes_processed;
    stats_.points_created += created.created.size();
    stats_.points_culled += static_cast<std::size_t>(culled_points);
    stats_.points_fused += static_cast<std::size_t>(fused);
    stats_.keyframes_culled += culled_keyframes.size();
    if (ba.ran) ++stats_.local_ba_runs;
    if (ba.aborted) ++stats_.local_ba_aborted;
    stats_.outliers_erased += ba.outliers_erased;
    if (ba.ran) stats_.last_local_ba = ba;
    stats_.last_timings = timings;
  }
  return keyframe->is_bad() ? nullptr : keyframe;
}

LocalMapperStatistics LocalMapper::statistics() const {
  std::lock_guard lock(stats_mutex_);
  return stats_;
}

}  // namespace ddl::mapping
