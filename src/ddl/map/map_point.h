#pragma once
// A 3D landmark: position in the world frame, the keyframe features that observe it, and the
// summaries projection matching needs (best descriptor, mean viewing direction, scale-invariance
// distance range). ORB-SLAM2 section III-C / IV.
// Thread-safety: every method locks the point's own mutex; any thread may call any method.
// Observations hold keyframes weakly; the Map owns entities.

#include <array>
#include <cstddef>
#include <cstdint>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <vector>

#include "ddl/core/types.h"
#include "ddl/features/orb_extractor.h"
#include "ddl/map/ids.h"

namespace ddl::map {

class KeyFrame;

class MapPoint : public std::enable_shared_from_this<MapPoint> {
 public:
  struct Observation {
    std::shared_ptr<KeyFrame> keyframe;
    std::size_t feature_index = 0;
    bool stereo = false;  // counted twice (add_observation)
  };

  MapPoint(MapPointId id, const Vec3d& p_w, const std::shared_ptr<KeyFrame>& reference_keyframe);

  MapPointId id() const { return id_; }
  /// Id of the keyframe that created the point (for culling by age).
  KeyFrameId first_keyframe_id() const { return first_keyframe_id_; }

  Vec3d position_w() const;
  void set_position_w(const Vec3d& p_w);

  /// Adds an observation; `stereo` counts twice as in ORB-SLAM2. Local mapping, fusion and loop
  /// closing pass mapping::has_stereo (ORB-SLAM2's u_right >= 0: a close point left of
  /// u = bf / z counts once). The tracker passes true for the points it creates from depth,
  /// whatever the sign of u_right: ORB-SLAM2's rule there culls more border points and was
  /// measured worse (stop 12: static_loop ATE 0.0057 -> 0.0065 m; docs/RESULTS.md).
  void add_observation(const std::shared_ptr<KeyFrame>& keyframe, std::size_t feature_index,
                       bool stereo);
  /// Removes the keyframe's observation. Returns true when the point has become bad
  /// (observation count <= 2) and was detached from every keyframe.
  bool erase_observation(KeyFrameId keyframe_id);
  /// Live observations sorted by keyframe id.
  std::vector<Observation> observations() const;
  /// Feature index in that keyframe, or -1.
  long index_in(KeyFrameId keyframe_id) const;
  bool is_in(KeyFrameId keyframe_id) const { return index_in(keyframe_id) >= 0; }
  /// Weighted observation count (stereo observations count 2).
  int num_observations() const;
  /// The number of keyframes that observe the point (each once, with or without depth).
  std::size_t num_keyframes() const;

  std::shared_ptr<KeyFrame> reference_keyframe() const;

  /// Descriptor with the least median Hamming distance to the others (ORB-SLAM2).
  cv::Mat descriptor() const;
  void compute_distinctive_descriptor();
  /// Recomputes the mean viewing direction and [min, max] distance of scale invariance.
  void update_normal_and_depth();
  Vec3d normal_w() const;
  double min_distance() const;
  double max_distance() const;
  /// Pyramid level at which the point should be seen from `distance_m`.
  int predict_scale(double distance_m, const features::ScalePyramid& pyramid) const;

  /// What projection matching reads about a point, copied under one lock (tracking tests
  /// thousands of points per frame). Fields equal the accessors of the same name.
  struct ViewSummary {
    Vec3d p_w = Vec3d::Zero();
    Vec3d normal_w = Vec3d::Zero();
    double min_distance = 0.0;
    double max_distance = 0.0;
    bool bad = false;
    double level0_distance_m = 0.0;  // unscaled distance behind predict_scale()
    /// The same as MapPoint::predict_scale at the time of the copy.
    int predict_scale(double distance_m, const features::ScalePyramid& pyramid) const;
  };
  ViewSummary view_summary() const;

  void increase_visible(int n = 1);
  void increase_found(int n = 1);
  /// found / visible: how often the point was matched when it should have been seen.
  double found_ratio() const;
  int found_count() const;
  int visible_count() const;

  bool is_bad() const;
  /// Detaches the point from all keyframes and marks it bad. The Map removes it from its index.
  void set_bad();
  /// Moves all observations to `other` (fusion) and marks this point bad; afterwards
  /// replaced_by() returns `other`.
  void replace_with(const std::shared_ptr<MapPoint>& other);
  std::shared_ptr<MapPoint> replaced_by() const;

 private:
  struct Obs {
    std::weak_ptr<KeyFrame> keyframe;
    std::size_t feature_index;
    bool stereo;
  };

  const MapPointId id_;
  const KeyFrameId first_keyframe_id_;
  mutable std::mutex mutex_;
  Vec3d p_w_;
  Vec3d normal_w_ = Vec3d::Zero();
  double min_distance_ = 0.0;
  double max_distance_ = 0.0;
  std::array<std::uint8_t, 32> descriptor_{};  // 256-bit ORB descriptor
  bool has_descriptor_ = false;
  std::map<KeyFrameId, Obs> observations_;
  int num_obs_ = 0;
  std::weak_ptr<KeyFrame> reference_keyframe_;
  int visible_ = 1;
  int found_ = 1;
  bool bad_ = false;
  std::weak_ptr<MapPoint> replaced_by_;
};

using MapPointPtr = std::shared_ptr<MapPoint>;

}  // namespace ddl::map
