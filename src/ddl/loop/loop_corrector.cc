#include "ddl/loop/loop_corrector.h"

#include <spdlog/spdlog.h>

#include <vector>

#include "ddl/mapping/keyframe_matching.h"

namespace ddl::loop {

LoopCorrectionStatistics correct_loop(const map::KeyFramePtr& current, const LoopMatch& loop,
                                      map::Map& map, const mapping::CameraIntrinsics& camera,
                                      const LoopCorrectionConfig& config,
                                      const optimization::OptimizerConfig& optimizer) {
  LoopCorrectionStatistics stats;
  current->update_connections();

  // The current keyframe's neighbourhood, ordered by id.
  std::map<map::KeyFrameId, map::KeyFramePtr> connected;
  connected[current->id()] = current;
  for (const map::KeyFramePtr& kf : current->covisibles()) {
    if (!kf->is_bad()) connected[kf->id()] = kf;
  }

  EssentialGraphInput graph;
  graph.loop_keyframe = loop.matched;
  graph.current_keyframe = current;
  graph.min_weight = config.essential_graph_min_weight;
  const SE3 T_w_cur = current->T_w_c();
  for (const auto& [id, kf] : connected) {
    const SE3 T_i_w = kf->T_c_w();
    graph.non_corrected_T_c_w[id] = T_i_w;
    // Each neighbour keeps its pose relative to the current keyframe.
    graph.corrected_T_c_w[id] = (T_i_w * T_w_cur) * loop.T_cur_w_corrected;
  }

  mapping::FuseParams fuse_params;
  fuse_params.radius_factor = config.fuse_radius;
  fuse_params.max_hamming = config.fuse_max_hamming;
  fuse_params.check_reprojection = false;  // the corrected poses are not refined yet
  fuse_params.conflict = mapping::FuseConflict::kPreferProjected;

  map.apply_frame_change([&] {
    // 1. Points first (they use the poses before the correction), then the poses; the points'
    // normals and depth ranges last, from the corrected camera centres.
    std::vector<map::MapPointPtr> moved;
    for (const auto& [id, kf] : connected) {
      const SE3 T_w_corrected = graph.corrected_T_c_w.at(id).inverse();
      const SE3& T_c_w_before = graph.non_corrected_T_c_w.at(id);
      for (const map::MapPointPtr& point : kf->map_point_set()) {
        if (graph.corrected_points.count(point->id()) != 0) continue;
        point->set_position_w(T_w_corrected * (T_c_w_before * point->position_w()));
        graph.corrected_points[point->id()] = id;
        moved.push_back(point);
      }
    }
    for (const auto& [id, kf] : connected) {
      kf->set_T_c_w(graph.corrected_T_c_w.at(id));
      kf->update_connections();
    }
    for (const map::MapPointPtr& point : moved) point->update_normal_and_depth();
    stats.corrected_keyframes = connected.size();
    stats.corrected_points = graph.corrected_points.size();

    // 2. Loop fusion: the verified matches first...
    const map::FrameFeatures& features = current->features();
    for (std::size_t i = 0; i < loop.current_matches.size(); ++i) {
      const map::MapPointPtr& loop_point = loop.current_matches[i];
      if (!loop_point || loop_point->is_bad()) continue;
      const map::MapPointPtr own = current->map_point(i);
      if (own == loop_point) continue;
      if (own && !own->is_bad()) {
        own->replace_with(loop_point);
        map.erase_map_point(own->id());
        ++stats.replaced_points;
      } else if (!loop_point->is_in(current->id())) {
        current->set_map_point(i, loop_point);
        loop_point->add_observation(current, i, mapping::has_stereo(features, i));
        loop_point->compute_distinctive_descriptor();
      }
    }
    // ... then every loop point into every corrected keyframe.
    for (const auto& [id, kf] : connected) {
      stats.fused_points += mapping::fuse(kf, graph.corrected_T_c_w.at(id), loop.loop_points,
                                          camera, fuse_params, map);
    }
  });

  // 3. New links across the loop.
  for (const auto& [id, kf] : connected) {
    std::set<map::KeyFrameId> before;
    for (const map::KeyFramePtr& other : kf->covisibles()) before.insert(other->id());
    kf->update_connections();
    std::set<map::KeyFrameId>& links = graph.loop_connections[id];
    // Every keyframe it shares a point with now (ORB-SLAM2 LoopConnections): the current and
    // the loop keyframe get their edge even when they share fewer than 15 points.
    for (const map::KeyFramePtr& other : kf->connected_keyframes()) {
      if (before.count(other->id()) != 0 || connected.count(other->id()) != 0) continue;
      links.insert(other->id());
    }
    stats.loop_links += links.size();
  }
  stats.essential_graph = optimize_essential_graph(map, graph, optimizer);

  // 4. The loop edge (it also protects both keyframes from culling).
  loop.matched->add_loop_edge(current);
  current->add_loop_edge(loop.matched);
  map.notify_big_change();
  spdlog::info(
      "loop closed: keyframe {} with {}: {} keyframes and {} points corrected, {} points "
      "replaced, {} fused, {} new links; essential graph {} vertices, {} edges, cost {:.4g} -> "
      "{:.4g}",
      current->id(), loop.matched->id(), stats.corrected_keyframes, stats.corrected_points,
      stats.replaced_points, stats.fused_points, stats.loop_links, stats.essential_graph.vertices,
      stats.essential_graph.edges, stats.essential_graph.initial_cost,
      stats.essential_graph.final_cost);
  return stats;
}

}  // namespace ddl::loop
