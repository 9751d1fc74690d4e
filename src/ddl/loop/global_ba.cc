#include "ddl/loop/global_ba.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <deque>
#include <set>
#include <vector>

#include "ddl/optimization/bundle_adjustment.h"

namespace ddl::loop {

GlobalBaResult run_global_bundle_adjustment(const map::Map& map,
                                            const mapping::CameraIntrinsics& camera,
                                            const optimization::OptimizerConfig& config,
                                            const std::atomic<bool>* abort) {
  GlobalBaResult out;
  optimization::BundleAdjustmentProblem problem;
  problem.camera = camera;
  std::vector<map::KeyFramePtr> keyframes;
  std::vector<map::MapPointPtr> points;
  map.read_consistent([&] {
    keyframes = map.keyframes();  // by id: keyframes[0] is the first keyframe, the gauge
    std::map<map::KeyFrameId, std::size_t> index;
    for (const map::KeyFramePtr& kf : keyframes) {
      index[kf->id()] = problem.keyframes.size();
      problem.keyframes.push_back({kf->T_c_w(), false});
    }
    for (map::MapPointPtr& point : map.map_points()) {
      const std::vector<map::MapPoint::Observation> observations = point->observations();
      const std::size_t point_index = points.size();
      bool used = false;
      for (const auto& obs : observations) {
        auto it = index.find(obs.keyframe->id());
        if (it == index.end()) continue;
        optimization::BaObservation o;
        o.keyframe = it->second;
        o.point = point_index;
        o.measurement = mapping::measurement_of(obs.keyframe->features(), obs.feature_index);
        problem.observations.push_back(o);
        used = true;
      }
      if (!used) continue;
      problem.points_w.push_back(point->position_w());
      points.push_back(std::move(point));
    }
  });
  out.observations = problem.observations.size();
  if (problem.observations.empty()) return out;

  optimization::SolveControl control;
  control.abort = abort;
  const optimization::BundleAdjustmentResult result =
      optimization::global_bundle_adjustment(problem, config, control);
  out.aborted = result.aborted;
  out.failed = result.failed;
  out.iterations = result.iterations;
  out.initial_cost = result.initial_cost;
  out.final_cost = result.final_cost;
  for (std::size_t k = 0; k < keyframes.size(); ++k)
    out.T_c_w[keyframes[k]->id()] = result.T_c_w[k];
  for (std::size_t p = 0; p < points.size(); ++p)
    out.points_w[points[p]->id()] = result.points_w[p];
  spdlog::debug("global BA: {} keyframes, {} points, {} observations, {} iterations{}",
                keyframes.size(), points.size(), out.observations, out.iterations,
                out.aborted ? ", aborted" : "");
  return out;
}

std::size_t merge_global_bundle_adjustment(map::Map& map, const GlobalBaResult& result) {
  // A solve of a map that a reset has cleared since (ids are never reused, so none of its
  // keyframes comes back): nothing to write, and no correction to announce, which would make the
  // dense stage rebuild its octree and the followers of map corrections drop a frame's data.
  const std::vector<map::KeyFramePtr> present = map.keyframes();
  if (std::none_of(present.begin(), present.end(),
                   [&](const map::KeyFramePtr& kf) { return result.T_c_w.count(kf->id()) != 0; })) {
    return 0;
  }
  std::size_t updated = 0;
  map.apply_frame_change([&] {
    const std::vector<map::KeyFramePtr> keyframes = map.keyframes();
    std::map<map::KeyFrameId, SE3> new_pose;  // the pose each keyframe gets
    std::map<map::KeyFrameId, SE3> old_pose;  // its pose before the merge
    for (const map::KeyFramePtr& kf : keyframes) {
      auto it = result.T_c_w.find(kf->id());
      if (it != result.T_c_w.end()) new_pose[kf->id()] = it->second;
    }
    // Spanning tree from the first keyframe: keyframes the solve did not see follow their parent.
    std::deque<map::KeyFramePtr> queue;
    std::set<map::KeyFrameId> visited;
    if (const map::KeyFramePtr root = map.first_keyframe();
        root && new_pose.count(root->id()) != 0) {
      queue.push_back(root);
      visited.insert(root->id());
    }
    while (!queue.empty()) {
      const map::KeyFramePtr kf = queue.front();
      queue.pop_front();
      const SE3 T_w_c_before = kf->T_w_c();
      const SE3& T_c_w_after = new_pose.at(kf->id());
      for (const map::KeyFramePtr& child : kf->children()) {
        if (child->is_bad() || !visited.insert(child->id()).second) continue;
        if (new_pose.count(child->id()) == 0) {
          new_pose[child->id()] = (child->T_c_w() * T_w_c_before) * T_c_w_after;
        }
        queue.push_back(child);
      }
      old_pose[kf->id()] = kf->T_c_w();
      kf->set_T_c_w(T_c_w_after);
      ++updated;
    }
    // Keyframes outside the tree that the solve saw.
    for (const map::KeyFramePtr& kf : keyframes) {
      if (visited.count(kf->id()) != 0) continue;
      auto it = new_pose.find(kf->id());
      if (it == new_pose.end()) continue;
      old_pose[kf->id()] = kf->T_c_w();
      kf->set_T_c_w(it->second);
      ++updated;
    }
    for (const map::MapPointPtr& point : map.map_points()) {
      auto it = result.points_w.find(point->id());
      if (it != result.points_w.end()) {
        point->set_position_w(it->second);
      } else {
        // Created after the snapshot: move with the reference keyframe.
        const map::KeyFramePtr ref = point->reference_keyframe();
        if (!ref) continue;
        auto before = old_pose.find(ref->id());
        auto after = new_pose.find(ref->id());
        if (before == old_pose.end() || after == new_pose.end()) continue;
        point->set_position_w(after->second.inverse() * (before->second * point->position_w()));
      }
      point->update_normal_and_depth();
    }
  });
  map.notify_big_change();
  return updated;
}

}  // namespace ddl::loop
