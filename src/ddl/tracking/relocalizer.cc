#include "ddl/tracking/relocalizer.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <map>
#include <opencv2/calib3d.hpp>
#include <unordered_map>

namespace ddl::tracking {

Relocalizer::Relocalizer(const RelocalizationConfig& config, int bow_levels_up,
                         std::shared_ptr<const map::Map> map,
                         std::shared_ptr<const vocabulary::Vocabulary> vocabulary,
                         std::shared_ptr<const vocabulary::BowDatabase> keyframe_database)
    : config_(config),
      bow_levels_up_(bow_levels_up),
      map_(std::move(map)),
      vocabulary_(std::move(vocabulary)),
      database_(std::move(keyframe_database)) {}

std::vector<map::KeyFramePtr> Relocalizer::candidates(const vocabulary::BowVector& bow) const {
  std::vector<map::KeyFramePtr> out;
  if (bow.empty() || !database_) return out;
  const std::vector<vocabulary::QueryResult> results = database_->query(bow, 0);

  // Keyframes sharing enough words (ORB-SLAM2: more than 80% of the best one's shared words).
  std::uint32_t max_shared = 0;
  for (const auto& r : results) max_shared = std::max(max_shared, r.shared_words);
  const float min_shared = config_.min_common_words_ratio * static_cast<float>(max_shared);
  struct Candidate {
    map::KeyFramePtr keyframe;
    double score;
  };
  std::map<map::KeyFrameId, Candidate> by_id;
  for (const auto& r : results) {
    if (static_cast<float>(r.shared_words) <= min_shared) continue;
    map::KeyFramePtr kf = map_->keyframe(r.entry_id);
    if (!kf || kf->is_bad()) continue;
    by_id.emplace(r.entry_id, Candidate{std::move(kf), r.score});
  }
  if (by_id.empty()) return out;

  // Group score: a candidate plus its covisible candidates; the group is represented by its
  // best-scoring member.
  struct Group {
    double score;
    map::KeyFramePtr best;
    double best_score;
  };
  std::vector<Group> groups;
  double best_group_score = 0.0;
  for (const auto& [id, c] : by_id) {
    Group g{c.score, c.keyframe, c.score};
    for (const map::KeyFramePtr& n :
         c.keyframe->best_covisibles(static_cast<std::size_t>(config_.covisibles_for_score))) {
      auto it = by_id.find(n->id());
      if (it == by_id.end()) continue;
      g.score += it->second.score;
      if (it->second.score > g.best_score) {
        g.best_score = it->second.score;
        g.best = it->second.keyframe;
      }
    }
    best_group_score = std::max(best_group_score, g.score);
    groups.push_back(std::move(g));
  }
  const double min_score = config_.min_score_ratio * best_group_score;
  std::vector<std::pair<double, map::KeyFramePtr>> kept;
  for (Group& g : groups) {
    if (g.score <= min_score) continue;
    const bool seen = std::any_of(kept.begin(), kept.end(),
                                  [&](const auto& k) { return k.second->id() == g.best->id(); });
    if (!seen) kept.emplace_back(g.score, std::move(g.best));
  }
  std::stable_sort(kept.begin(), kept.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second->id() < b.second->id();
  });
  out.reserve(kept.size());
  for (auto& k : kept) out.push_back(std::move(k.second));
  return out;
}

bool Relocalizer::solve_pnp(Frame& frame, const std::vector<map::MapPointPtr>& matches) {
  const FrameGeometry& g = frame.geometry();
  std::vector<cv::Point3d> object_points;
  std::vector<cv::Point2d> image_points;
  std::vector<std::size_t> slots;
  for (std::size_t i = 0; i < matches.size(); ++i) {
    if (!matches[i]) continue;
    const Vec3d p_w = matches[i]->position_w();
    object_points.emplace_back(p_w.x(), p_w.y(), p_w.z());
    const cv::Point2f& pt = frame.features().keypoints[i].pt;
    image_points.emplace_back(pt.x, pt.y);
    slots.push_back(i);
  }
  if (object_points.size() < 6) return false;
  const cv::Matx33d K(g.fx, 0.0, g.cx, 0.0, g.fy, g.cy, 0.0, 0.0, 1.0);
  cv::Mat rvec;
  cv::Mat tvec;
  std::vector<int> inliers;
  // OpenCV's RANSAC seeds its own generator with a constant: the result is deterministic.
  const bool ok = cv::solvePnPRansac(object_points, image_points, K, cv::noArray(), rvec, tvec,
                                     false, config_.pnp_iterations, config_.pnp_reprojection_px,
                                     config_.pnp_confidence, inliers, cv::SOLVEPNP_EPNP);
  if (!ok || static_cast<int>(inliers.size()) < config_.pnp_min_inliers) return false;
  const Vec3d r(rvec.at<double>(0), rvec.at<double>(1), rvec.at<double>(2));
  const Vec3d t(tvec.at<double>(0), tvec.at<double>(1), tvec.at<double>(2));
  if (!r.allFinite() || !t.allFinite()) return false;
  frame.set_T_c_w(SE3(so3_exp(r), t));
  frame.clear_map_points();
  for (int k : inliers) {
    const std::size_t slot = slots[static_cast<std::size_t>(k)];
    frame.set_map_point(slot, matches[slot]);
  }
  return true;
}

void mark_already_found(const Frame& frame, bool with_rejected, IdMarks& marks) {
  marks.next_round();
  for (const map::MapPointPtr& p : frame.map_points()) {
    if (p) marks.mark(p->id());
  }
  if (with_rejected) {
    for (map::MapPointId id : frame.rejected_points()) marks.mark(id);
  }
}

RelocalizationResult Relocalizer::relocalize(Frame& frame, FrameMatcher& matcher,
                                             FramePoseEstimator& estimator) {
  RelocalizationResult result;
  frame.compute_bow(*vocabulary_, bow_levels_up_);
  const std::vector<map::KeyFramePtr> keyframes = candidates(frame.features().bow);
  result.candidates = static_cast<int>(keyframes.size());

  for (const map::KeyFramePtr& kf : keyframes) {
    if (kf->is_bad()) continue;
    frame.clear_map_points();
    frame.clear_rejected_points();
    const int bow_matches = matcher.match_bow(*kf, frame, config_.bow_ratio, matches_);
    if (bow_matches < config_.min_bow_matches) {
      spdlog::debug("relocalization: candidate keyframe {}: {} BoW matches", kf->id(), bow_matches);
      continue;
    }
    if (!solve_pnp(frame, matches_)) {
      spdlog::debug("relocalization: candidate keyframe {}: {} BoW matches, PnP failed", kf->id(),
                    bow_matches);
      continue;
    }

    int good = estimator.optimize(frame);
    if (good < config_.pnp_min_inliers) {
      spdlog::debug("relocalization: candidate keyframe {}: {} BoW matches, {} PnP inliers kept",
                    kf->id(), bow_matches, good);
      continue;
    }
    discard_outliers(frame);

    if (good < config_.min_inliers) {
      // More matches by projecting the candidate's points with the estimated pose. Not searched:
      // the PnP inliers, including those the optimisation has just rejected (ORB-SLAM2's sFound).
      mark_already_found(frame, /*with_rejected=*/true, found_);
      const int added = matcher.match_keyframe_projection(
          frame, *kf, found_, config_.search_radius_px, config_.search_max_distance);
      if (added + good >= config_.min_inliers) {
        good = estimator.optimize(frame);
        if (good > config_.retry_inliers && good < config_.min_inliers) {
          // Almost there: a narrower search around the better pose. Not searched: the current
          // matches, outliers of the last optimisation included (they are still in their slots).
          mark_already_found(frame, /*with_rejected=*/false, found_);
          const int more = matcher.match_keyframe_projection(
              frame, *kf, found_, config_.retry_radius_px, config_.retry_max_distance);
          if (good + more >= config_.min_inliers) good = estimator.optimize(frame);
        }
        discard_outliers(frame);
      }
    }
    spdlog::debug("relocalization: candidate keyframe {}: {} BoW matches, {} inliers", kf->id(),
                  bow_matches, good);
    if (good >= config_.min_inliers) {
      // Outliers of this search are not excluded from the local-map search that follows.
      frame.clear_rejected_points();
      result.success = true;
      result.inliers = good;
      result.keyframe = kf;
      return result;
    }
  }
  frame.clear_map_points();
  return result;
}

}  // namespace ddl::tracking
