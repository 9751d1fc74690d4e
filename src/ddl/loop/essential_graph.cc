#include "ddl/loop/essential_graph.h"

#include <utility>
#include <vector>

#include "ddl/optimization/pose_graph.h"

namespace ddl::loop {

EssentialGraphStatistics optimize_essential_graph(map::Map& map, const EssentialGraphInput& input,
                                                  const optimization::OptimizerConfig& config) {
  EssentialGraphStatistics stats;
  const std::vector<map::KeyFramePtr> keyframes = map.keyframes();
  std::map<map::KeyFrameId, std::size_t> index;
  optimization::PoseGraphProblem problem;
  std::vector<SE3> initial;  // vertex poses before optimisation (corrected where available)
  for (const map::KeyFramePtr& kf : keyframes) {
    index[kf->id()] = problem.vertices.size();
    auto it = input.corrected_T_c_w.find(kf->id());
    const SE3 T = it != input.corrected_T_c_w.end() ? it->second : kf->T_c_w();
    problem.vertices.push_back({T, kf->id() == input.loop_keyframe->id()});
    initial.push_back(T);
  }
  if (index.count(input.loop_keyframe->id()) == 0) return stats;

  // Relative pose measurements use the poses before the correction where there is one.
  auto measured_T_c_w = [&](map::KeyFrameId id) {
    auto it = input.non_corrected_T_c_w.find(id);
    return it != input.non_corrected_T_c_w.end() ? it->second : initial[index.at(id)];
  };
  std::set<std::pair<map::KeyFrameId, map::KeyFrameId>> inserted;
  auto add_edge = [&](map::KeyFrameId a, map::KeyFrameId b, const SE3& T_a_w, const SE3& T_b_w) {
    optimization::PoseGraphEdge edge;
    edge.i = index.at(a);
    edge.j = index.at(b);
    edge.T_i_j = T_a_w * T_b_w.inverse();
    problem.edges.push_back(edge);
  };

  // New loop links: measured with the corrected poses (they are what closes the loop).
  for (const auto& [id, linked] : input.loop_connections) {
    if (index.count(id) == 0) continue;
    const map::KeyFramePtr kf = map.keyframe(id);
    if (!kf) continue;
    for (const map::KeyFrameId other : linked) {
      if (index.count(other) == 0) continue;
      const bool the_loop =
          id == input.current_keyframe->id() && other == input.loop_keyframe->id();
      if (!the_loop && kf->weight(other) < input.min_weight) continue;
      add_edge(id, other, initial[index.at(id)], initial[index.at(other)]);
      inserted.emplace(std::min(id, other), std::max(id, other));
    }
  }

  for (const map::KeyFramePtr& kf : keyframes) {
    const map::KeyFrameId id = kf->id();
    const SE3 T_i_w = measured_T_c_w(id);
    // Spanning tree.
    const map::KeyFramePtr parent = kf->parent();
    if (parent && index.count(parent->id()) != 0) {
      add_edge(parent->id(), id, measured_T_c_w(parent->id()), T_i_w);
    }
    // Earlier loop edges.
    std::set<map::KeyFrameId> loop_edges;
    for (const map::KeyFramePtr& other : kf->loop_edges()) {
      loop_edges.insert(other->id());
      if (other->id() < id && index.count(other->id()) != 0) {
        add_edge(other->id(), id, measured_T_c_w(other->id()), T_i_w);
      }
    }
    // Strong covisibility.
    std::set<map::KeyFrameId> children;
    for (const map::KeyFramePtr& child : kf->children()) children.insert(child->id());
    for (const map::KeyFramePtr& other : kf->covisibles_with_min_weight(input.min_weight)) {
      const map::KeyFrameId oid = other->id();
      if (parent && oid == parent->id()) continue;
      if (children.count(oid) != 0 || loop_edges.count(oid) != 0) continue;
      if (oid >= id || index.count(oid) == 0) continue;
      if (inserted.count({std::min(id, oid), std::max(id, oid)}) != 0) continue;
      add_edge(oid, id, measured_T_c_w(oid), T_i_w);
    }
  }
  stats.vertices = problem.vertices.size();
  stats.edges = problem.edges.size();

  const optimization::PoseGraphResult result = optimization::optimize_pose_graph(problem, config);
  stats.iterations = result.iterations;
  stats.initial_cost = result.initial_cost;
  stats.final_cost = result.final_cost;

  map.apply_frame_change([&] {
    for (std::size_t k = 0; k < keyframes.size(); ++k) keyframes[k]->set_T_c_w(result.T_c_w[k]);
    // Points follow the keyframe that placed them: T_after^-1 * T_before.
    for (const map::MapPointPtr& point : map.map_points()) {
      map::KeyFrameId ref_id = 0;
      auto corrected = input.corrected_points.find(point->id());
      if (corrected != input.corrected_points.end()) {
        ref_id = corrected->second;
      } else {
        const map::KeyFramePtr ref = point->reference_keyframe();
        if (!ref) continue;
        ref_id = ref->id();
      }
      auto it = index.find(ref_id);
      if (it == index.end()) continue;
      const SE3 T_w_after = result.T_c_w[it->second].inverse();
      point->set_position_w(T_w_after * (initial[it->second] * point->position_w()));
      point->update_normal_and_depth();
    }
  });
  return stats;
}

}  // namespace ddl::loop
