#include "ddl/loop/loop_verification.h"

#include <spdlog/spdlog.h>

#include <map>

#include "ddl/loop/loop_matching.h"
#include "ddl/loop/relative_pose.h"
#include "ddl/optimization/pose_optimization.h"

namespace ddl::loop {
namespace {

int count_matches(const std::vector<map::MapPointPtr>& matches) {
  int n = 0;
  for (const auto& p : matches) n += p ? 1 : 0;
  return n;
}

/// Pose-only refinement of the current keyframe against the matched points; outlier matches are
/// cleared. Returns the refined pose and the inlier count.
std::pair<SE3, int> refine_pose(const map::KeyFrame& current, const SE3& T_c_w_initial,
                                std::vector<map::MapPointPtr>& matches,
                                const mapping::CameraIntrinsics& camera,
                                const optimization::OptimizerConfig& optimizer) {
  const map::FrameFeatures& features = current.features();
  std::vector<optimization::PoseObservation> observations;
  std::vector<std::size_t> slots;
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if (!matches[i]) continue;
    observations.push_back({matches[i]->position_w(), mapping::measurement_of(features, i)});
    slots.push_back(i);
  }
  const optimization::PoseOptimizationResult result =
      optimization::optimize_pose(camera, T_c_w_initial, observations, optimizer);
  if (!result.optimized) return {T_c_w_initial, 0};
  for (std::size_t k = 0; k < slots.size(); ++k) {
    if (!result.inliers[k]) matches[slots[k]].reset();
  }
  return {result.T_c_w, result.num_inliers};
}

std::optional<LoopMatch> verify_candidate(const map::KeyFramePtr& current,
                                          const map::KeyFramePtr& candidate,
                                          const mapping::CameraIntrinsics& camera,
                                          const LoopVerificationConfig& config,
                                          const optimization::OptimizerConfig& optimizer) {
  LoopMatch loop;
  loop.matched = candidate;
  // 1. BoW matches between the two keyframes' points.
  const std::vector<map::MapPointPtr> bow_matches = search_by_bow(
      *current, *candidate, config.bow_ratio, config.max_hamming, config.check_orientation);
  loop.bow_matches = count_matches(bow_matches);
  if (loop.bow_matches < config.min_bow_matches) {
    spdlog::debug("loop verification: keyframe {} vs {}: {} BoW matches (< {})", current->id(),
                  candidate->id(), loop.bow_matches, config.min_bow_matches);
    return std::nullopt;
  }

  // 2. 3D-3D RANSAC: points in each camera's coordinates.
  const map::FrameFeatures& f1 = current->features();
  const map::FrameFeatures& f2 = candidate->features();
  const SE3 T1_c_w = current->T_c_w();
  const SE3 T2_c_w = candidate->T_c_w();
  std::vector<PointCorrespondence> correspondences;
  std::vector<std::size_t> slots;
  for (std::size_t i = 0; i < bow_matches.size(); ++i) {
    const map::MapPointPtr& p2 = bow_matches[i];
    if (!p2) continue;
    const map::MapPointPtr p1 = current->map_point(i);
    const long i2 = p2->index_in(candidate->id());
    if (!p1 || p1->is_bad() || i2 < 0) continue;
    const cv::KeyPoint& kp1 = f1.keypoints[i];
    const cv::KeyPoint& kp2 = f2.keypoints[static_cast<std::size_t>(i2)];
    PointCorrespondence c;
    c.p1_c = T1_c_w * p1->position_w();
    c.p2_c = T2_c_w * p2->position_w();
    c.uv1 = Vec2d(kp1.pt.x, kp1.pt.y);
    c.uv2 = Vec2d(kp2.pt.x, kp2.pt.y);
    c.sigma2_1 = f1.pyramid.level_sigma2[static_cast<std::size_t>(kp1.octave)];
    c.sigma2_2 = f2.pyramid.level_sigma2[static_cast<std::size_t>(kp2.octave)];
    correspondences.push_back(c);
    slots.push_back(i);
  }
  RelativePoseRansacOptions ransac;
  ransac.max_iterations = config.ransac_max_iterations;
  ransac.probability = config.ransac_probability;
  ransac.min_inliers = config.ransac_min_inliers;
  ransac.chi2 = config.ransac_chi2;
  // A seed per (keyframe, candidate) pair: the same input always draws the same samples.
  ransac.seed = config.seed ^ (current->id() * 0x9E3779B97F4A7C15ULL) ^
                (candidate->id() * 0xC2B2AE3D27D4EB4FULL);
  const std::optional<RelativePoseEstimate> estimate =
      estimate_relative_pose(correspondences, camera, ransac);
  if (!estimate) {
    spdlog::debug("loop verification: keyframe {} vs {}: {} BoW matches, no RANSAC model",
                  current->id(), candidate->id(), loop.bow_matches);
    return std::nullopt;
  }
  loop.ransac_inliers = estimate->num_inliers;

  // 3. More matches with the candidate's points at the estimated pose, then refinement.
  std::vector<map::MapPointPtr> matches(f1.size());
  for (std::size_t k = 0; k < slots.size(); ++k) {
    if (estimate->inliers[k]) matches[slots[k]] = bow_matches[slots[k]];
  }
  SE3 T_cur_w = estimate->T_1_2 * T2_c_w;
  const std::vector<map::MapPointPtr> candidate_points = candidate->map_point_set();
  search_by_projection(*current, T_cur_w, candidate_points, matches, camera,
                       config.candidate_search_radius, config.max_hamming);
  auto [T_refined, inliers] = refine_pose(*current, T_cur_w, matches, camera, optimizer);
  loop.refined_inliers = inliers;
  if (inliers < config.min_refined_inliers) {
    spdlog::debug("loop verification: keyframe {} vs {}: {} RANSAC inliers, {} after refinement",
                  current->id(), candidate->id(), loop.ransac_inliers, inliers);
    return std::nullopt;
  }
  T_cur_w = T_refined;

  // 4. Every point of the candidate's neighbourhood, projected at the refined pose.
  loop.loop_keyframes = candidate->covisibles();
  loop.loop_keyframes.push_back(candidate);
  std::map<map::MapPointId, map::MapPointPtr> loop_points;
  for (const map::KeyFramePtr& kf : loop.loop_keyframes) {
    for (map::MapPointPtr& p : kf->map_point_set()) loop_points.emplace(p->id(), std::move(p));
  }
  for (auto& [id, p] : loop_points) loop.loop_points.push_back(std::move(p));
  search_by_projection(*current, T_cur_w, loop.loop_points, matches, camera,
                       config.loop_search_radius, config.max_hamming);
  const int total = count_matches(matches);
  if (total < config.min_loop_matches) {
    spdlog::debug("loop verification: keyframe {} vs {}: {} loop matches (< {})", current->id(),
                  candidate->id(), total, config.min_loop_matches);
    return std::nullopt;
  }
  auto [T_final, final_inliers] = refine_pose(*current, T_cur_w, matches, camera, optimizer);
  if (final_inliers < config.min_refined_inliers) return std::nullopt;
  loop.T_cur_w_corrected = T_final;
  loop.T_cur_matched = T_final * T2_c_w.inverse();
  loop.current_matches = std::move(matches);
  loop.loop_matches = final_inliers;
  return loop;
}

}  // namespace

int confirm_loop_in(const map::KeyFramePtr& neighbour, const map::KeyFramePtr& current,
                    const LoopMatch& loop, const mapping::CameraIntrinsics& camera,
                    const LoopVerificationConfig& config,
                    const optimization::OptimizerConfig& optimizer) {
  if (!neighbour || neighbour->is_bad()) return 0;
  const SE3 T_n_cur = neighbour->T_c_w() * current->T_c_w().inverse();
  const SE3 T_n_w = T_n_cur * loop.T_cur_w_corrected;
  // Points the neighbour observes already would match its own features wherever the loop puts
  // it near its present pose: evidence of nothing (review, stop 25).
  std::vector<map::MapPointPtr> foreign_points;
  foreign_points.reserve(loop.loop_points.size());
  for (const map::MapPointPtr& point : loop.loop_points) {
    if (!point->is_in(neighbour->id())) foreign_points.push_back(point);
  }
  std::vector<map::MapPointPtr> matches(neighbour->features().size());
  search_by_projection(*neighbour, T_n_w, foreign_points, matches, camera,
                       config.loop_search_radius, config.max_hamming);
  const int matched = count_matches(matches);
  if (matched < config.min_refined_inliers) return 0;
  return refine_pose(*neighbour, T_n_w, matches, camera, optimizer).second;
}

std::optional<LoopMatch> verify_loop_candidates(const map::KeyFramePtr& current,
                                                const std::vector<map::KeyFramePtr>& candidates,
                                                const mapping::CameraIntrinsics& camera,
                                                const LoopVerificationConfig& config,
                                                const optimization::OptimizerConfig& optimizer) {
  for (const map::KeyFramePtr& candidate : candidates) {
    if (!candidate || candidate->is_bad()) continue;
    if (auto loop = verify_candidate(current, candidate, camera, config, optimizer)) {
      spdlog::debug(
          "loop verification: keyframe {} vs {}: {} BoW matches, {} RANSAC inliers, {} refined, "
          "{} loop matches",
          current->id(), candidate->id(), loop->bow_matches, loop->ransac_inliers,
          loop->refined_inliers, loop->loop_matches);
      return loop;
    }
  }
  return std::nullopt;
}

}  // namespace ddl::loop
