#include "ddl/loop/loop_detector.h"

#include <spdlog/spdlog.h>

#include <algorithm>
#include <map>
#include <string>
#include <unordered_map>
#include <unordered_set>

namespace ddl::loop {

LoopDetector::LoopDetector(const LoopDetectionConfig& config, std::shared_ptr<map::Map> map,
                           std::shared_ptr<vocabulary::BowDatabase> database)
    : config_(config), map_(std::move(map)), database_(std::move(database)) {}

std::vector<map::KeyFramePtr> LoopDetector::candidates(const map::KeyFramePtr& keyframe) const {
  const vocabulary::BowVector& bow = keyframe->bow();
  if (bow.empty()) return {};
  // 1. The lowest score among the covisibles: a loop candidate must look at least as similar.
  double min_score = 1.0;
  for (const map::KeyFramePtr& kf : keyframe->covisibles()) {
    if (kf->is_bad() || !kf->has_bow()) continue;
    min_score = std::min(min_score, vocabulary::l1_score(bow, kf->bow()));
  }

  // 2. Database query without the keyframe and every keyframe it shares a point with (ORB-SLAM2
  // GetConnectedKeyFrames). Until 2026-11-26 only the covisibles of weight >= 15 were left out,
  // so a recent keyframe sharing a few points could be taken for a loop (found by review).
  std::unordered_set<vocabulary::EntryId> exclude;
  exclude.insert(keyframe->id());
  for (const map::KeyFramePtr& kf : keyframe->connected_keyframes()) exclude.insert(kf->id());
  const std::vector<vocabulary::QueryResult> results = database_->query(bow, 0, 0.0, exclude);
  if (results.empty()) return {};
  std::uint32_t max_common = 0;
  for (const auto& r : results) {
    if (r.entry_id < keyframe->id()) max_common = std::max(max_common, r.shared_words);
  }
  const double min_common = config_.min_common_words_ratio * max_common;
  // Scores of every keyframe sharing enough words (neighbours add theirs in step 3).
  std::unordered_map<map::KeyFrameId, double> scores;
  std::vector<std::pair<double, map::KeyFrameId>> matched;
  for (const auto& r : results) {
    if (r.entry_id >= keyframe->id()) continue;  // only keyframes older than this one
    if (static_cast<double>(r.shared_words) <= min_common) continue;
    scores[r.entry_id] = r.score;
    if (r.score >= min_score) matched.emplace_back(r.score, r.entry_id);
  }
  if (matched.empty()) return {};
  std::sort(matched.begin(), matched.end(), [](const auto& a, const auto& b) {
    return a.first != b.first ? a.first > b.first : a.second < b.second;
  });

  // 3. Accumulated score over each candidate's best covisibles; the group's best keyframe.
  std::vector<std::pair<double, map::KeyFramePtr>> groups;
  double best_group_score = 0.0;
  for (const auto& [score, id] : matched) {
    map::KeyFramePtr kf = map_->keyframe(id);
    if (!kf || kf->is_bad()) continue;
    double accumulated = score;
    double best_score = score;
    map::KeyFramePtr best = kf;
    for (const map::KeyFramePtr& neighbour :
         kf->best_covisibles(static_cast<std::size_t>(config_.score_covisibles))) {
      auto it = scores.find(neighbour->id());
      if (it == scores.end()) continue;
      accumulated += it->second;
      if (it->second > best_score) {
        best_score = it->second;
        best = neighbour;
      }
    }
    groups.emplace_back(accumulated, best);
    best_group_score = std::max(best_group_score, accumulated);
  }
  const double min_group_score = config_.min_group_score_ratio * best_group_score;
  std::map<map::KeyFrameId, map::KeyFramePtr> kept;
  for (const auto& [accumulated, kf] : groups) {
    if (accumulated > min_group_score && !kf->is_bad()) kept.emplace(kf->id(), kf);
  }
  std::vector<map::KeyFramePtr> out;
  for (auto& [id, kf] : kept) out.push_back(std::move(kf));
  return out;
}

LoopDetector::Detection LoopDetector::detect(const map::KeyFramePtr& keyframe) {
  const map::KeyFramePtr first = map_->first_keyframe();
  const map::KeyFrameId since = std::max(last_loop_keyframe_, first ? first->id() : 0);
  if (keyframe->id() < since + static_cast<map::KeyFrameId>(config_.min_keyframes_between_loops)) {
    return {};
  }
  const std::vector<map::KeyFramePtr> found = candidates(keyframe);
  if (found.empty()) {
    consistent_groups_.clear();
    return {};
  }
  Detection detection;

  // 4. Covisibility consistency with the groups of the previous keyframes.
  std::vector<std::pair<Group, int>> current_groups;
  std::vector<bool> group_extended(consistent_groups_.size(), false);
  std::vector<map::KeyFramePtr>& accepted = detection.consistent;
  for (const map::KeyFramePtr& candidate : found) {
    Group group;
    group.insert(candidate->id());
    for (const map::KeyFramePtr& kf : candidate->connected_keyframes()) group.insert(kf->id());

    bool enough = false;
    bool consistent_with_some = false;
    for (std::size_t g = 0; g < consistent_groups_.size(); ++g) {
      const Group& previous = consistent_groups_[g].first;
      const bool consistent = std::any_of(
          group.begin(), group.end(), [&](map::KeyFrameId id) { return previous.count(id) != 0; });
      if (!consistent) continue;
      consistent_with_some = true;
      const int consistency = consistent_groups_[g].second + 1;
      if (!group_extended[g]) {
        current_groups.emplace_back(group, consistency);
        group_extended[g] = true;
      }
      if (consistency >= config_.consistency_threshold && !enough) {
        accepted.push_back(candidate);
        enough = true;
      }
    }
    if (!consistent_with_some) {
      // Threshold 0: every candidate goes to geometric verification at once.
      if (config_.consistency_threshold == 0 && !enough) {
        accepted.push_back(candidate);
        enough = true;
      }
      current_groups.emplace_back(std::move(group), 0);
    }
    if (!enough) detection.pending.push_back(candidate);
  }
  consistent_groups_ = std::move(current_groups);
  if (spdlog::should_log(spdlog::level::debug)) {
    std::string ids;
    for (const map::KeyFramePtr& kf : found) ids += fmt::format(" {}", kf->id());
    std::string groups;
    for (const auto& [group, consistency] : consistent_groups_) {
      groups +=
          fmt::format(" [{} keyframes from {}: {}]", group.size(), *group.begin(), consistency);
    }
    spdlog::debug("loop detection: keyframe {}: candidates{}; groups{}; {} consistent",
                  keyframe->id(), ids, groups, accepted.size());
  }
  return detection;
}

}  // namespace ddl::loop
