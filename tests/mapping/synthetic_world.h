#pragma once
// Synthetic RGB-D worlds with exact ground truth for the local mapping and loop closing tests:
// 3D points with a random 256-bit descriptor each, observed by keyframes whose features are the
// exact projections plus small noise, a few flipped descriptor bits per observation, depth from
// the projection plus Kinect-like noise, and a pyramid level consistent with the distance (as ORB
// detects a patch of fixed physical size at a level that shrinks with the distance). A small
// "tracker" turns views into keyframes and map points the way tracking does (points tracked from
// the last keyframes, new points from depth), optionally at drifted poses.
// Everything is drawn from std::mt19937_64 with fixed seeds, so tests are reproducible.

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <opencv2/core.hpp>
#include <random>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"
#include "ddl/features/feature_grid.h"
#include "ddl/features/orb_extractor.h"
#include "ddl/map/map.h"
#include "ddl/vocabulary/bow_database.h"
#include "ddl/vocabulary/descriptor.h"
#include "ddl/vocabulary/vocabulary.h"
#include "ddl/vocabulary/vocabulary_training.h"

namespace ddl::test {

inline constexpr double kBf = 40.0;  // ORB-SLAM2 TUM virtual baseline times fx [m px]

inline double rad(double degrees) { return degrees * M_PI / 180.0; }
inline double deg(double radians) { return radians * 180.0 / M_PI; }

/// Standard normal from the generator (Box-Muller; fully specified, unlike
/// std::normal_distribution).
inline double gaussian(std::mt19937_64& rng) {
  const double u1 = (static_cast<double>(rng() >> 11) + 0.5) * (1.0 / 9007199254740992.0);
  const double u2 = (static_cast<double>(rng() >> 11) + 0.5) * (1.0 / 9007199254740992.0);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * M_PI * u2);
}

inline double uniform(std::mt19937_64& rng, double lo, double hi) {
  return lo + (hi - lo) * (static_cast<double>(rng() >> 11) * (1.0 / 9007199254740992.0));
}

inline vocabulary::Descriptor random_descriptor(std::mt19937_64& rng) {
  return vocabulary::Descriptor{rng(), rng(), rng(), rng()};
}

inline vocabulary::Descriptor flip_bits(vocabulary::Descriptor d, int bits, std::mt19937_64& rng) {
  for (int k = 0; k < bits; ++k) {
    const auto b = static_cast<int>(rng() % vocabulary::kDescriptorBits);
    d[static_cast<std::size_t>(b / 64)] ^= std::uint64_t{1} << (b % 64);
  }
  return d;
}

struct WorldPoint {
  Vec3d p_w;
  vocabulary::Descriptor descriptor;
  double level_at_1m;  // pyramid level at 1 m; level(d) = level_at_1m - log(d) / log(1.2)
  float angle_deg;     // keypoint orientation
};

/// Camera pose (T_c_w) at center_w looking along the horizontal direction `yaw` (about world y;
/// yaw 0 looks along +z). The camera's y axis is world +y: the world is "y down" like the camera.
inline SE3 look_along(const Vec3d& center_w, double yaw_rad) {
  // Camera z (forward) = (sin yaw, 0, cos yaw); x (right) = (cos yaw, 0, -sin yaw); y = (0, 1, 0).
  Mat3d R_w_c;
  R_w_c.col(0) = Vec3d(std::cos(yaw_rad), 0.0, -std::sin(yaw_rad));
  R_w_c.col(1) = Vec3d(0.0, 1.0, 0.0);
  R_w_c.col(2) = Vec3d(std::sin(yaw_rad), 0.0, std::cos(yaw_rad));
  return SE3(R_w_c, center_w).inverse();  // T_c_w
}

struct ViewOptions {
  double pixel_sigma = 0.3;        // keypoint noise at level 0 [px] (times the level scale)
  double depth_sigma_k = 0.001;    // depth noise sigma = k * z^2 [m]
  int max_flipped_bits = 3;        // each observation flips 0..max bits of the descriptor
  int clutter = 20;                // features of nothing (random descriptor and position)
  double no_depth_fraction = 0.0;  // fraction of point features without depth
  double max_depth_m = 8.0;
};

/// One keyframe's worth of features and, per feature, the world point it observes (-1: clutter).
struct View {
  std::shared_ptr<map::FrameFeatures> features;
  std::vector<int> point_of_feature;
};

class SyntheticWorld {
 public:
  camera::PinholeCamera camera;  // 640 x 480, f = 525
  features::ScalePyramid pyramid = features::make_scale_pyramid(8, 1.2);
  std::vector<WorldPoint> points;
  std::shared_ptr<const vocabulary::Vocabulary> vocabulary;
  int bow_levels_up = 2;  // the test vocabulary has 3 levels: direct index at depth 1

  /// The world most tests build maps in: n points on the walls of a 5 x 5 x 3 m room and a
  /// vocabulary trained on them (room(), then train_vocabulary(), from the same generator).
  static SyntheticWorld trained_room(std::size_t n, std::mt19937_64& rng) {
    SyntheticWorld world;
    world.points = room(n, 2.5, 1.5, rng);
    world.train_vocabulary(rng);
    return world;
  }

  /// Points on the four walls, floor and ceiling of a box room centred at the origin.
  static std::vector<WorldPoint> room(std::size_t n, double half_size_m, double half_height_m,
                                      std::mt19937_64& rng) {
    std::vector<WorldPoint> out;
    out.reserve(n);
    for (std::size_t i = 0; i < n; ++i) {
      WorldPoint p;
      const auto wall = static_cast<int>(rng() % 4);
      const double s = uniform(rng, -half_size_m, half_size_m);
      const double h = uniform(rng, -half_height_m, half_height_m);
      switch (wall) {
        case 0:
          p.p_w = Vec3d(s, h, half_size_m);
          break;
        case 1:
          p.p_w = Vec3d(s, h, -half_size_m);
          break;
        case 2:
          p.p_w = Vec3d(half_size_m, h, s);
          break;
        default:
          p.p_w = Vec3d(-half_size_m, h, s);
          break;
      }
      p.descriptor = random_descriptor(rng);
      p.level_at_1m = uniform(rng, 3.8, 8.8);  // levels 0..4 at 2-3 m
      p.angle_deg = static_cast<float>(uniform(rng, 0.0, 360.0));
      out.push_back(p);
    }
    return out;
  }

  /// Trains a small vocabulary (branching 10, 3 levels) on noisy views of the points.
  void train_vocabulary(std::mt19937_64& rng) {
    std::vector<cv::Mat> images;
    for (std::size_t start = 0; start < points.size(); start += 100) {
      std::vector<vocabulary::Descriptor> ds;
      for (std::size_t i = start; i < std::min(points.size(), start + 100); ++i) {
        ds.push_back(flip_bits(points[i].descriptor, static_cast<int>(rng() % 4), rng));
      }
      images.push_back(vocabulary::descriptors_to_mat(ds));
    }
    vocabulary::VocabularyConfig config;
    config.branching = 10;
    config.levels = 3;
    config.seed = 7;
    vocabulary = std::make_shared<const vocabulary::Vocabulary>(
        vocabulary::train_vocabulary(images, config));
  }

  int level_at(const WorldPoint& p, double distance_m) const {
    const double level = p.level_at_1m - std::log(distance_m) / pyramid.log_scale_factor;
    return std::clamp(static_cast<int>(std::lround(level)), 0, pyramid.num_levels - 1);
  }

  /// Features of the points visible from T_c_w (true pose), in point order, then clutter.
  View observe(const SE3& T_c_w, std::mt19937_64& rng, const ViewOptions& options = {},
               bool with_bow = true) const {
    View view;
    auto f = std::make_shared<map::FrameFeatures>();
    f->pyramid = pyramid;
    std::vector<vocabulary::Descriptor> descriptors;
    const Vec3d center = T_c_w.inverse().translation();
    auto push = [&](const cv::KeyPoint& kp, const vocabulary::Descriptor& d, float depth, int id) {
      f->keypoints.push_back(kp);
      descriptors.push_back(d);
      f->depth_m.push_back(depth);
      f->u_right.push_back(depth > 0.0f ? static_cast<float>(kp.pt.x - kBf / depth) : -1.0f);
      view.point_of_feature.push_back(id);
    };
    for (std::size_t i = 0; i < points.size(); ++i) {
      const WorldPoint& p = points[i];
      const Vec3d p_c = T_c_w * p.p_w;
      if (p_c.z() < 0.3 || p_c.z() > options.max_depth_m) continue;
      const Vec2d uv = camera.project(p_c);
      if (!camera.in_image(uv, 20.0)) continue;
      const double distance = (p.p_w - center).norm();
      const int level = level_at(p, distance);
      const double sigma = options.pixel_sigma * pyramid.scale_factors[level];
      cv::KeyPoint kp;
      kp.pt = cv::Point2f(static_cast<float>(uv.x() + sigma * gaussian(rng)),
                          static_cast<float>(uv.y() + sigma * gaussian(rng)));
      kp.octave = level;
      kp.angle = static_cast<float>(std::fmod(p.angle_deg + 0.5 * gaussian(rng) + 360.0, 360.0));
      kp.size = 31.0f * pyramid.scale_factors[level];
      float depth =
          static_cast<float>(p_c.z() + options.depth_sigma_k * p_c.z() * p_c.z() * gaussian(rng));
      if (uniform(rng, 0.0, 1.0) < options.no_depth_fraction) depth = 0.0f;
      const int bits =
          static_cast<int>(rng() % static_cast<unsigned>(options.max_flipped_bits + 1));
      push(kp, flip_bits(p.descriptor, bits, rng), depth, static_cast<int>(i));
    }
    for (int c = 0; c < options.clutter; ++c) {
      cv::KeyPoint kp;
      kp.pt = cv::Point2f(static_cast<float>(uniform(rng, 20, camera.width - 21)),
                          static_cast<float>(uniform(rng, 20, camera.height - 21)));
      kp.octave = static_cast<int>(rng() % 4);
      kp.angle = static_cast<float>(uniform(rng, 0.0, 360.0));
      kp.size = 31.0f * pyramid.scale_factors[static_cast<std::size_t>(kp.octave)];
      push(kp, random_descriptor(rng), static_cast<float>(uniform(rng, 1.0, 4.0)), -1);
    }
    f->descriptors = vocabulary::descriptors_to_mat(descriptors);
    f->grid = features::FeatureGrid(f->keypoints, cv::Rect2f(0.0f, 0.0f, 640.0f, 480.0f));
    if (with_bow && vocabulary) {
      vocabulary->transform(f->descriptors, bow_levels_up, f->bow, f->feature_vector);
    }
    view.features = std::move(f);
    return view;
  }
};

/// Builds keyframes as tracking would: world points seen by one of the last `track_window`
/// keyframes are tracked (the feature gets that map point; local mapping adds the observation),
/// others with depth get a new map point back-projected at the keyframe's estimated pose (with
/// the observation added, as tracking's new-keyframe points). Keeps the truth per keyframe/point.
class FakeTracker {
 public:
  FakeTracker(std::shared_ptr<map::Map> map, const SyntheticWorld& world, int track_window = 2)
      : map_(std::move(map)), world_(world), track_window_(track_window) {}

  /// A new keyframe observing `view` (taken at the true pose) placed at T_c_w_estimated.
  map::KeyFramePtr make_keyframe(const View& view, const SE3& T_c_w_estimated, double t_s) {
    const map::KeyFrameId id = map_->next_keyframe_id();
    auto kf = std::make_shared<map::KeyFrame>(id, t_s, view.features, T_c_w_estimated);
    const int index = static_cast<int>(keyframe_count_++);
    const map::FrameFeatures& f = *view.features;
    for (std::size_t i = 0; i < f.size(); ++i) {
      const int wp = view.point_of_feature[i];
      if (wp < 0) continue;
      auto it = instances_.find(wp);
      if (it != instances_.end() && !it->second.point->is_bad() &&
          index - it->second.last_seen <= track_window_ && !it->second.point->is_in(id)) {
        kf->set_map_point(i, it->second.point);
        it->second.last_seen = index;
        continue;
      }
      if (f.depth_m[i] <= 0.0f) continue;
      const cv::Point2f& pt = f.keypoints[i].pt;
      const double z = f.depth_m[i];
      const Vec3d p_c((pt.x - world_.camera.cx) / world_.camera.fx * z,
                      (pt.y - world_.camera.cy) / world_.camera.fy * z, z);
      auto point = std::make_shared<map::MapPoint>(map_->next_map_point_id(),
                                                   T_c_w_estimated.inverse() * p_c, kf);
      point->add_observation(kf, i, true);
      kf->set_map_point(i, point);
      point->compute_distinctive_descriptor();
      point->update_normal_and_depth();
      map_->add_map_point(point);
      instances_[wp] = Instance{point, index};
      truth_of_point_[point->id()] = wp;
    }
    return kf;
  }

  /// World point a map point was created for (-1 if unknown).
  int truth_of(map::MapPointId id) const {
    auto it = truth_of_point_.find(id);
    return it == truth_of_point_.end() ? -1 : it->second;
  }

 private:
  struct Instance {
    map::MapPointPtr point;
    int last_seen = 0;
  };
  std::shared_ptr<map::Map> map_;
  const SyntheticWorld& world_;
  int track_window_;
  std::size_t keyframe_count_ = 0;
  std::map<int, Instance> instances_;
  std::map<map::MapPointId, int> truth_of_point_;
};

/// Camera-centre distance and rotation angle between two T_c_w poses.
inline double center_error_m(const SE3& a_T_c_w, const SE3& b_T_c_w) {
  return (a_T_c_w.inverse().translation() - b_T_c_w.inverse().translation()).norm();
}
inline double rotation_error_deg(const SE3& a, const SE3& b) {
  return deg((a * b.inverse()).rotation_angle());
}

}  // namespace ddl::test
