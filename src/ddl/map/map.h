#pragma once
// The map: owns every keyframe and map point (ARCHITECTURE.md section 3: the only shared mutable
// state). Entities lock inside their own methods; the Map's own index is guarded by its mutex.
// Ids come from per-map counters (no global state).
//
// Consistency across several calls: tracking reads poses and points while local mapping and loop
// closing change them. Writers that move many entities at once run inside `apply_update(f)`
// (local BA write-back) or `apply_frame_change(f)` (loop correction, global BA merge: they move
// the world frame), and readers that need a consistent view of several entities run inside
// `read_consistent(f)`; all take the map's update lock around f, so a reader never sees half a
// correction. The lock itself is never exposed.

#include <atomic>
#include <cstdint>
#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <shared_mutex>
#include <vector>

#include "ddl/map/keyframe.h"
#include "ddl/map/map_point.h"

namespace ddl::map {

class Map {
 public:
  Map() = default;
  Map(const Map&) = delete;
  Map& operator=(const Map&) = delete;

  KeyFrameId next_keyframe_id() { return next_keyframe_id_.fetch_add(1); }
  MapPointId next_map_point_id() { return next_map_point_id_.fetch_add(1); }
  /// Raises the id counters to at least these values (a map loaded from a file: new keyframes
  /// and points must not take the ids of loaded ones).
  void reserve_ids(KeyFrameId next_keyframe_id, MapPointId next_map_point_id);

  /// Adds the keyframe, unless it was made for the map that clear() emptied (its id is below
  /// the floor clear() returned): then nothing happens and false is returned. The first keyframe
  /// added to an empty map becomes its origin (KeyFrame::mark_origin).
  bool add_keyframe(const KeyFramePtr& keyframe);
  /// Adds the point, unless it was made by a keyframe of the map that clear() emptied
  /// (MapPoint::first_keyframe_id below the floor): then false.
  bool add_map_point(const MapPointPtr& point);
  /// Removes a keyframe that KeyFrame::set_bad() culled, and the points it left with too few
  /// observations (they became bad when it detached from them).
  void erase_culled_keyframe(const KeyFramePtr& keyframe);
  /// Removes a point from the index (call after MapPoint::set_bad).
  void erase_map_point(MapPointId id);

  /// Live keyframes / points sorted by id (bad ones are skipped).
  std::vector<KeyFramePtr> keyframes() const;
  std::vector<MapPointPtr> map_points() const;
  KeyFramePtr keyframe(KeyFrameId id) const;
  std::size_t keyframe_count() const;
  std::size_t map_point_count() const;
  KeyFramePtr first_keyframe() const;

  /// Runs f under the exclusive update lock (writers moving many entities within the world
  /// frame: local BA).
  void apply_update(const std::function<void()>& f);
  /// apply_update() for a write that moves the world frame as a whole around the current camera
  /// (loop correction, essential graph, global BA merge): poses estimated before it are in the
  /// old frame. Counted under the lock (frame_change_count).
  void apply_frame_change(const std::function<void()>& f);
  /// How many apply_frame_change() calls have run: a reader that compares two readings taken
  /// under read_consistent() knows whether such a write came in between. Local BA does not count:
  /// it refines points and poses where they are.
  std::uint64_t frame_change_count() const { return frame_change_count_.load(); }
  /// Runs f under the shared update lock (readers needing a consistent multi-entity view).
  void read_consistent(const std::function<void()>& f) const;

  /// Incremented after every loop correction or global BA write-back, so that other stages
  /// (dense map, inpainting caches) know that keyframe poses moved.
  int big_change_index() const { return big_change_index_.load(); }
  void notify_big_change() { big_change_index_.fetch_add(1); }

  /// Drops everything (e.g. a reset after tracking failure at start-up) and returns the floor:
  /// every keyframe id reserved before the call is below it. Keyframes and points of the old map
  /// are refused from then on, so a stage that was still working on one when the tracker reset
  /// the map (local mapping in its own thread) cannot put it back.
  KeyFrameId clear();

 private:
  std::atomic<KeyFrameId> next_keyframe_id_{0};
  std::atomic<MapPointId> next_map_point_id_{0};
  std::atomic<int> big_change_index_{0};
  std::atomic<std::uint64_t> frame_change_count_{0};
  mutable std::mutex index_mutex_;
  std::map<KeyFrameId, KeyFramePtr> keyframes_;
  std::map<MapPointId, MapPointPtr> points_;
  KeyFrameId floor_ = 0;  // see clear()
  mutable std::shared_mutex update_mutex_;
};

}  // namespace ddl::map
