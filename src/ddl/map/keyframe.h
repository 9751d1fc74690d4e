#pragma once
// A keyframe: a frame kept in the map with its features, pose, the map points its features
// observe, its covisibility links (weight = shared map points), its spanning-tree parent and its
// loop edges. ORB-SLAM2 section III-D.
// Thread-safety: every method locks the keyframe's own mutexes; any thread may call any method.
// Links to other keyframes are weak; the Map owns entities.

#include <atomic>
#include <cstddef>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <vector>

#include "ddl/core/se3.h"
#include "ddl/map/frame_features.h"
#include "ddl/map/ids.h"
#include "ddl/map/map_point.h"
#include "ddl/vocabulary/vocabulary.h"

namespace ddl::map {

class KeyFrame : public std::enable_shared_from_this<KeyFrame> {
 public:
  KeyFrame(KeyFrameId id, double timestamp_s, std::shared_ptr<const FrameFeatures> features,
           const SE3& T_c_w);

  KeyFrameId id() const { return id_; }
  double timestamp_s() const { return timestamp_s_; }
  const FrameFeatures& features() const { return *features_; }
  const std::shared_ptr<const FrameFeatures>& features_ptr() const { return features_; }

  // --- bag of words ---------------------------------------------------------------------------
  /// BoW vector and direct index of the keyframe's features: those of features() when the
  /// tracker computed them, else the ones given to set_bow() (local mapping computes them once
  /// for keyframes created without). Empty until either exists. Set once and never replaced, so
  /// the references stay valid for the keyframe's lifetime.
  const vocabulary::BowVector& bow() const;
  const vocabulary::FeatureVector& feature_vector() const;
  bool has_bow() const { return !bow().empty(); }
  /// Stores the BoW of a keyframe whose features came without one; no-op when it has one.
  void set_bow(vocabulary::BowVector bow, vocabulary::FeatureVector feature_vector);
  /// Computes and stores the BoW with `vocabulary` (direct index `levels_up` levels above the
  /// words) unless the keyframe has one or the vocabulary is empty (local mapping for keyframes
  /// created without one; keyframes loaded from a map file).
  void compute_bow(const vocabulary::Vocabulary& vocabulary, int levels_up);

  // --- pose -----------------------------------------------------------------------------------
  SE3 T_c_w() const;
  SE3 T_w_c() const;
  Vec3d camera_center_w() const;
  void set_T_c_w(const SE3& T_c_w);

  // --- map point associations (one slot per feature) -----------------------------------------
  MapPointPtr map_point(std::size_t feature_index) const;
  /// Snapshot of all slots (nullptr where a feature has no point).
  std::vector<MapPointPtr> map_points() const;
  /// Distinct good points observed by this keyframe.
  std::vector<MapPointPtr> map_point_set() const;
  void set_map_point(std::size_t feature_index, MapPointPtr point);
  void erase_map_point(std::size_t feature_index);
  /// Clears the slot only if it still holds `point`.
  void erase_map_point(const MapPoint& point);
  /// Points with at least `min_observations` observations.
  int tracked_map_points(int min_observations) const;

  // --- covisibility graph -------------------------------------------------------------------
  /// Recomputes links from the map points' observations (ORB-SLAM2 UpdateConnections: keep
  /// links of weight >= 15, or the strongest one). The first call also sets the spanning-tree
  /// parent to the strongest link (the next strongest when that one is being culled and refuses
  /// the child). Updates the other keyframes' links to this one.
  void update_connections();
  void add_connection(const std::shared_ptr<KeyFrame>& other, int weight);
  void erase_connection(KeyFrameId other_id);
  /// Up to n covisible keyframes, strongest first (ties: lower id first).
  std::vector<std::shared_ptr<KeyFrame>> best_covisibles(std::size_t n) const;
  std::vector<std::shared_ptr<KeyFrame>> covisibles() const;
  std::vector<std::shared_ptr<KeyFrame>> covisibles_with_min_weight(int min_weight) const;
  /// Every keyframe that shared at least one map point with this one at its last
  /// update_connections(), and those that linked to it since (ORB-SLAM2 GetConnectedKeyFrames,
  /// which loop detection excludes and groups by), by id. covisibles() keeps only weight >= 15.
  std::vector<std::shared_ptr<KeyFrame>> connected_keyframes() const;
  /// Weight of the covisibility link (0 below 15 shared points, unless it is the strongest).
  int weight(KeyFrameId other_id) const;

  // --- spanning tree and loop edges ----------------------------------------------------------
  std::shared_ptr<KeyFrame> parent() const;
  void set_parent(const std::shared_ptr<KeyFrame>& parent);
  std::vector<std::shared_ptr<KeyFrame>> children() const;
  /// false (nothing added) once set_bad() has begun: a keyframe being culled takes no children.
  bool add_child(const std::shared_ptr<KeyFrame>& child);
  void erase_child(KeyFrameId child_id);
  void add_loop_edge(const std::shared_ptr<KeyFrame>& other);
  std::vector<std::shared_ptr<KeyFrame>> loop_edges() const;

  // --- life cycle -----------------------------------------------------------------------------
  /// The first keyframe of its map (Map::add_keyframe marks it): the gauge of local BA, the root
  /// of the spanning tree, never culled. ORB-SLAM2 tests id 0, but ids are not reset with the map
  /// here (Map::clear), so after a reset the new map's first keyframe has a higher id.
  bool is_origin() const { return origin_.load(); }
  void mark_origin() { origin_.store(true); }
  /// Loop closing protects keyframes it is working with from culling.
  void set_not_erase(bool protect);
  bool is_erase_protected() const;
  /// set_not_erase(false) without the deferred culling: returns whether culling came while it
  /// was protected and is due now (the caller then calls set_bad()). A keyframe with loop edges
  /// stays protected and returns false.
  bool release_erase_protection();
  bool is_bad() const;
  /// Marks bad, detaches from points and covisibility, and re-parents its children in the
  /// spanning tree (ORB-SLAM2 SetBadFlag). The map's origin keyframe is never set bad.
  /// Returns false when it did nothing (protected, origin, or bad or being culled already); a
  /// protected keyframe is culled when its protection is released.
  bool set_bad();
  /// Pose relative to the parent, kept when the keyframe became bad so the camera trajectory
  /// can still be recovered through it.
  SE3 T_c_parent_at_removal() const;

 private:
  struct Link {
    std::weak_ptr<KeyFrame> keyframe;
    int weight;
  };
  void rebuild_ordered_locked();

  const KeyFrameId id_;
  const double timestamp_s_;
  const std::shared_ptr<const FrameFeatures> features_;

  struct Bow {
    vocabulary::BowVector bow;
    vocabulary::FeatureVector feature_vector;
  };
  mutable std::mutex bow_mutex_;
  std::unique_ptr<const Bow> bow_;  // set once by set_bow()

  mutable std::mutex pose_mutex_;
  SE3 T_c_w_;
  SE3 T_c_parent_;

  mutable std::mutex points_mutex_;
  std::vector<MapPointPtr> points_;

  mutable std::mutex graph_mutex_;
  std::map<KeyFrameId, Link> links_;
  std::vector<std::pair<int, KeyFrameId>> ordered_;          // weight desc, id asc
  std::map<KeyFrameId, std::weak_ptr<KeyFrame>> connected_;  // see connected_keyframes()
  std::weak_ptr<KeyFrame> parent_;
  std::map<KeyFrameId, std::weak_ptr<KeyFrame>> children_;
  std::map<KeyFrameId, std::weak_ptr<KeyFrame>> loop_edges_;
  bool first_connection_ = true;
  bool not_erase_ = false;
  bool to_be_erased_ = false;
  bool erasing_ = false;  // set_bad() has begun (bad_ is set when it is done)
  bool bad_ = false;
  std::atomic<bool> origin_{false};
};

using KeyFramePtr = std::shared_ptr<KeyFrame>;

}  // namespace ddl::map
