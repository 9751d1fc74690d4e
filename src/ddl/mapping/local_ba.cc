#include "ddl/mapping/local_ba.h"

#include <algorithm>
#include <map>
#include <vector>

#include "ddl/optimization/bundle_adjustment.h"

namespace ddl::mapping {

LocalBaStatistics run_local_bundle_adjustment(const map::KeyFramePtr& current, map::Map& map,
                                              const CameraIntrinsics& camera,
                                              const optimization::OptimizerConfig& config,
                                              const std::atomic<bool>* abort,
                                              std::size_t max_free_keyframes) {
  LocalBaStatistics stats;
  if (abort != nullptr && abort->load(std::memory_order_acquire)) {
    stats.aborted = true;
    return stats;
  }

  // Local keyframes (free): the current one and its covisibles; keyed by id for a fixed order.
  std::map<map::KeyFrameId, map::KeyFramePtr> local;
  local[current->id()] = current;
  const std::vector<map::KeyFramePtr> covisibles =
      max_free_keyframes > 0 ? current->best_covisibles(max_free_keyframes - 1)
                             : current->covisibles();
  for (const map::KeyFramePtr& kf : covisibles) {
    if (!kf->is_bad()) local[kf->id()] = kf;
  }
  // Local points: everything the local keyframes see.
  std::map<map::MapPointId, map::MapPointPtr> points;
  for (const auto& [id, kf] : local) {
    for (map::MapPointPtr& p : kf->map_point_set()) points.emplace(p->id(), std::move(p));
  }
  // Fixed keyframes: they see local points but are not local.
  std::map<map::KeyFrameId, map::KeyFramePtr> fixed;
  struct ObsRef {
    map::KeyFramePtr keyframe;
    map::MapPointPtr point;
  };
  optimization::BundleAdjustmentProblem problem;
  problem.camera = camera;
  std::vector<map::MapPoint::Observation> observations;  // gathered first, indexed after
  std::vector<std::vector<map::MapPoint::Observation>> point_observations;
  point_observations.reserve(points.size());
  for (const auto& [id, p] : points) {
    point_observations.push_back(p->observations());
    for (const auto& obs : point_observations.back()) {
      if (obs.keyframe->is_bad() || local.count(obs.keyframe->id()) != 0) continue;
      fixed.emplace(obs.keyframe->id(), obs.keyframe);
    }
  }

  std::map<map::KeyFrameId, std::size_t> kf_index;
  std::vector<map::KeyFramePtr> kf_list;
  for (const auto& [id, kf] : local) {
    kf_index[id] = kf_list.size();
    kf_list.push_back(kf);
    problem.keyframes.push_back({kf->T_c_w(), kf->is_origin()});  // the gauge
  }
  for (const auto& [id, kf] : fixed) {
    kf_index[id] = kf_list.size();
    kf_list.push_back(kf);
    problem.keyframes.push_back({kf->T_c_w(), true});
  }

  std::vector<map::MapPointPtr> point_list;
  std::vector<ObsRef> obs_refs;
  std::size_t pi = 0;
  for (const auto& [id, p] : points) {
    const std::size_t point_index = point_list.size();
    point_list.push_back(p);
    problem.points_w.push_back(p->position_w());
    for (const auto& obs : point_observations[pi]) {
      auto it = kf_index.find(obs.keyframe->id());
      if (it == kf_index.end()) continue;
      optimization::BaObservation o;
      o.keyframe = it->second;
      o.point = point_index;
      o.measurement = measurement_of(obs.keyframe->features(), obs.feature_index);
      problem.observations.push_back(o);
      obs_refs.push_back({obs.keyframe, p});
    }
    ++pi;
  }
  stats.free_keyframes = static_cast<std::size_t>(
      std::count_if(problem.keyframes.begin(), problem.keyframes.end(),
                    [](const optimization::BaKeyframe& kf) { return !kf.fixed; }));
  stats.fixed_keyframes = fixed.size();
  stats.points = point_list.size();
  stats.observations = problem.observations.size();
  if (problem.observations.empty()) return stats;

  optimization::SolveControl control;
  control.abort = abort;
  const optimization::BundleAdjustmentResult result =
      optimization::local_bundle_adjustment(problem, config, control);
  stats.ran = true;
  stats.aborted = result.aborted;
  stats.iterations = result.iterations;
  stats.initial_cost = result.initial_cost;
  stats.final_cost = result.final_cost;
  // Aborted before its first iteration (a keyframe arrived while the problem was built), or
  // failed: the map is left as it was, as ORB-SLAM2 does when its stop flag is up before
  // optimizing.
  if ((result.aborted && result.iterations == 0) || result.failed) return stats;

  map.apply_update([&] {
    for (const std::size_t i : result.outliers) {
      const ObsRef& ref = obs_refs[i];
      if (ref.point->is_bad()) continue;
      ref.keyframe->erase_map_point(*ref.point);
      ref.point->erase_observation(ref.keyframe->id());
      ++stats.outliers_erased;
    }
    for (std::size_t k = 0; k < local.size(); ++k) {
      if (!problem.keyframes[k].fixed) kf_list[k]->set_T_c_w(result.T_c_w[k]);
    }
    for (std::size_t p = 0; p < point_list.size(); ++p) {
      const map::MapPointPtr& point = point_list[p];
      if (point->is_bad()) {
        map.erase_map_point(point->id());
        continue;
      }
      point->set_position_w(result.points_w[p]);
      point->update_normal_and_depth();
    }
  });
  return stats;
}

}  // namespace ddl::mapping
