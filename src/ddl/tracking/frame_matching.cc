#include "ddl/tracking/frame_matching.h"

#include <cmath>
#include <cstdint>

namespace ddl::tracking {
namespace {

// Above every Hamming distance of 256-bit descriptors and every allowed threshold (the search
// distances may be configured up to 256): a search that met no free candidate must never pass
// `best_distance <= max_distance` (with 256 it did, and wrote the point onto keypoint 0).
constexpr int kNoMatch = 257;

const std::uint8_t* descriptor_row(const cv::Mat& descriptors, std::size_t i) {
  return descriptors.ptr<std::uint8_t>(static_cast<int>(i));
}

/// A slot may take a new match when it is free or holds a point nobody observes (ORB-SLAM2:
/// "Observations() > 0" protects a slot).
bool slot_taken(const Frame& frame, std::size_t i) {
  const map::MapPointPtr& p = frame.map_point(i);
  return p && p->num_observations() > 0;
}

/// ORB-SLAM2 RadiusByViewingCos: a point seen almost head-on is predicted more precisely.
float radius_by_viewing_cos(float view_cos) { return view_cos > 0.998f ? 2.5f : 4.0f; }

}  // namespace

bool project_in_frustum(const Frame& frame, const map::MapPointPtr& point, float min_view_cos,
                        PointProjection& out) {
  const FrameGeometry& g = frame.geometry();
  const map::MapPoint::ViewSummary view = point->view_summary();
  if (view.bad) return false;
  const Vec3d p_c = frame.T_c_w() * view.p_w;
  if (p_c.z() <= 0.0) return false;
  const Vec2d uv = g.project(p_c);
  if (!g.in_image(uv.x(), uv.y())) return false;

  const Vec3d ray = view.p_w - frame.camera_center_w();
  const double distance = ray.norm();
  if (distance < view.min_distance || distance > view.max_distance) return false;
  const double view_cos = ray.dot(view.normal_w) / distance;
  if (view_cos < min_view_cos) return false;

  out.point = point;
  out.u = static_cast<float>(uv.x());
  out.v = static_cast<float>(uv.y());
  out.u_right = static_cast<float>(uv.x() - g.bf / p_c.z());
  out.level = view.predict_scale(distance, frame.features().pyramid);
  out.view_cos = static_cast<float>(view_cos);
  return true;
}

int FrameMatcher::drop_inconsistent_rotations(Frame& frame) {
  int dropped = 0;
  for (int id : histogram_.inconsistent_ids()) {
    frame.clear_map_point(static_cast<std::size_t>(id));
    ++dropped;
  }
  return dropped;
}

int FrameMatcher::match_last_frame(Frame& current, const Frame& last, float radius_px) {
  const FrameGeometry& g = current.geometry();
  const map::FrameFeatures& cur = current.features();
  const map::FrameFeatures& prev = last.features();
  histogram_.clear();

  // Camera motion along the last camera's optical axis decides which pyramid levels can hold
  // the match: moving forward, points appear larger (coarser levels), backward finer levels.
  const Vec3d t_last_current = last.T_c_w() * current.camera_center_w();
  const bool forward = t_last_current.z() > g.baseline_m;
  const bool backward = -t_last_current.z() > g.baseline_m;

  filled_.assign(current.size(), 0);
  int matches = 0;
  for (std::size_t i = 0; i < last.size(); ++i) {
    const map::MapPointPtr& point = last.map_point(i);
    if (!point || last.is_outlier(i) || point->is_bad()) continue;
    const Vec3d p_c = current.T_c_w() * point->position_w();
    if (p_c.z() <= 0.0) continue;
    const Vec2d uv = g.project(p_c);
    if (!g.in_image(uv.x(), uv.y())) continue;

    const int last_level = prev.keypoints[i].octave;
    const float radius =
        radius_px * cur.pyramid.scale_factors[static_cast<std::size_t>(last_level)];
    int min_level = last_level - 1;
    int max_level = last_level + 1;
    if (forward) {
      min_level = last_level;
      max_level = features::FeatureGrid::kAnyLevel;
    } else if (backward) {
      min_level = 0;
      max_level = last_level;
    }
    cur.grid.features_in_area(static_cast<float>(uv.x()), static_cast<float>(uv.y()), radius,
                              min_level, max_level, features::SearchWindow::kSquare, candidates_);
    if (candidates_.empty()) continue;

    const float u_right = static_cast<float>(uv.x() - g.bf / p_c.z());
    const cv::Mat descriptor = point->descriptor();
    if (descriptor.empty()) continue;
    const std::uint8_t* d_point = descriptor.ptr<std::uint8_t>(0);
    int best_distance = kNoMatch;
    std::size_t best_index = 0;
    for (std::size_t j : candidates_) {
      if (filled_[j] != 0 || slot_taken(current, j)) continue;
      if (cur.u_right[j] > 0.0f && std::fabs(u_right - cur.u_right[j]) > radius) continue;
      const int distance = features::hamming_distance(d_point, descriptor_row(cur.descriptors, j));
      if (distance < best_distance) {
        best_distance = distance;
        best_index = j;
      }
    }
    if (best_distance <= features::kThHigh) {
      filled_[best_index] = 1;
      current.set_map_point(best_index, point);
      current.set_outlier(best_index, false);
      histogram_.add(prev.keypoints[i].angle, cur.keypoints[best_index].angle,
                     static_cast<int>(best_index));
      ++matches;
    }
  }
  return matches - drop_inconsistent_rotations(current);
}

int FrameMatcher::match_projections(Frame& frame, const std::vector<PointProjection>& projections,
                                    float radius_factor, float ratio) {
  const map::FrameFeatures& f = frame.features();
  int matches = 0;
  for (const PointProjection& proj : projections) {
    if (proj.point->is_bad()) continue;
    const float level_scale = f.pyramid.scale_factors[static_cast<std::size_t>(proj.level)];
    const float radius = radius_by_viewing_cos(proj.view_cos) * radius_factor * level_scale;
    f.grid.features_in_area(proj.u, proj.v, radius, proj.level - 1, proj.level,
                            features::SearchWindow::kSquare, candidates_);
    if (candidates_.empty()) continue;
    const cv::Mat descriptor = proj.point->descriptor();
    if (descriptor.empty()) continue;
    const std::uint8_t* d_point = descriptor.ptr<std::uint8_t>(0);

    features::NearestTwo nearest;
    for (std::size_t j : candidates_) {
      if (slot_taken(frame, j)) continue;
      if (f.u_right[j] > 0.0f && std::fabs(proj.u_right - f.u_right[j]) > radius) continue;
      nearest.offer(features::hamming_distance(d_point, descriptor_row(f.descriptors, j)),
                    static_cast<int>(j), f.keypoints[j].octave);
    }
    if (!nearest.found() || nearest.best > features::kThHigh) continue;
    // ORB-SLAM2: the ratio test only between candidates of the same pyramid level.
    if (nearest.best_level == nearest.second_level &&
        static_cast<float>(nearest.best) > ratio * static_cast<float>(nearest.second)) {
      continue;
    }
    const auto best_index = static_cast<std::size_t>(nearest.best_index);
    frame.set_map_point(best_index, proj.point);
    frame.set_outlier(best_index, false);
    ++matches;
  }
  return matches;
}

int FrameMatcher::match_bow(const map::KeyFrame& keyframe, const Frame& frame, float ratio,
                            std::vector<map::MapPointPtr>& matches) {
  const map::FrameFeatures& kf = keyframe.features();
  const map::FrameFeatures& f = frame.features();
  matches.assign(frame.size(), nullptr);
  histogram_.clear();
  const std::vector<map::MapPointPtr> kf_points = keyframe.map_points();

  int count = 0;
  // The keyframe's direct index may come from local mapping (KeyFrame::set_bow).
  const vocabulary::FeatureVector& kf_vector = keyframe.feature_vector();
  auto kf_it = kf_vector.begin();
  auto f_it = f.feature_vector.begin();
  const auto kf_end = kf_vector.end();
  const auto f_end = f.feature_vector.end();
  while (kf_it != kf_end && f_it != f_end) {
    if (kf_it->node_id < f_it->node_id) {
      ++kf_it;
      continue;
    }
    if (f_it->node_id < kf_it->node_id) {
      ++f_it;
      continue;
    }
    for (std::uint32_t kf_index : kf_it->feature_indices) {
      const map::MapPointPtr& point = kf_points[kf_index];
      if (!point || point->is_bad()) continue;
      const std::uint8_t* d_kf = descriptor_row(kf.descriptors, kf_index);
      features::NearestTwo nearest;
      for (std::uint32_t f_index : f_it->feature_indices) {
        if (matches[f_index]) continue;
        nearest.offer(features::hamming_distance(d_kf, descriptor_row(f.descriptors, f_index)),
                      static_cast<int>(f_index));
      }
      if (nearest.found() && nearest.best <= features::kThLow &&
          static_cast<float>(nearest.best) < ratio * static_cast<float>(nearest.second)) {
        const auto best_index = static_cast<std::size_t>(nearest.best_index);
        matches[best_index] = point;
        histogram_.add(kf.keypoints[kf_index].angle, f.keypoints[best_index].angle,
                       static_cast<int>(best_index));
        ++count;
      }
    }
    ++kf_it;
    ++f_it;
  }
  for (int id : histogram_.inconsistent_ids()) {
    matches[static_cast<std::size_t>(id)].reset();
    --count;
  }
  return count;
}

int FrameMatcher::match_keyframe_projection(Frame& frame, const map::KeyFrame& keyframe,
                                            const IdMarks& already_found, float radius_px,
                                            int max_distance) {
  const FrameGeometry& g = frame.geometry();
  const map::FrameFeatures& f = frame.features();
  const map::FrameFeatures& kf = keyframe.features();
  histogram_.clear();
  const std::vector<map::MapPointPtr> kf_points = keyframe.map_points();

  int matches = 0;
  for (std::size_t i = 0; i < kf_points.size(); ++i) {
    const map::MapPointPtr& point = kf_points[i];
    if (!point || already_found.is_marked(point->id())) continue;
    const map::MapPoint::ViewSummary view = point->view_summary();
    if (view.bad) continue;
    const Vec3d p_c = frame.T_c_w() * view.p_w;
    if (p_c.z() <= 0.0) continue;
    const Vec2d uv = g.project(p_c);
    if (!g.in_image(uv.x(), uv.y())) continue;
    const double distance = (view.p_w - frame.camera_center_w()).norm();
    if (distance < view.min_distance || distance > view.max_distance) continue;
    const int level = view.predict_scale(distance, f.pyramid);
    const float radius = radius_px * f.pyramid.scale_factors[static_cast<std::size_t>(level)];
    f.grid.features_in_area(static_cast<float>(uv.x()), static_cast<float>(uv.y()), radius,
                            level - 1, level + 1, features::SearchWindow::kSquare, candidates_);
    if (candidates_.empty()) continue;
    const cv::Mat descriptor = point->descriptor();
    if (descriptor.empty()) continue;
    const std::uint8_t* d_point = descriptor.ptr<std::uint8_t>(0);
    int best_distance = kNoMatch;
    std::size_t best_index = 0;
    for (std::size_t j : candidates_) {
      if (frame.map_point(j)) continue;
      const int d = features::hamming_distance(d_point, descriptor_row(f.descriptors, j));
      if (d < best_distance) {
        best_distance = d;
        best_index = j;
      }
    }
    if (best_distance <= max_distance) {
      frame.set_map_point(best_index, point);
      frame.set_outlier(best_index, false);
      histogram_.add(kf.keypoints[i].angle, f.keypoints[best_index].angle,
                     static_cast<int>(best_index));
      ++matches;
    }
  }
  return matches - drop_inconsistent_rotations(frame);
}

}  // namespace ddl::tracking
