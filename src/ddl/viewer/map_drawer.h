#pragma once
// The map panel of the viewer (ORB-SLAM2's MapDrawer, drawn without OpenGL): the map points, the
// keyframes as frusta joined by their spanning tree, and the current camera, rendered by a
// virtual pinhole camera that follows the current camera from behind and above.
//
// Frames: w = world (the map's), c = a camera (x right, y down, z forward), v = the virtual view
// camera (same convention). Thread-safety: snapshot_map() reads the map under its shared update
// lock (the map locks inside); the rest are pure functions.

#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "ddl/core/se3.h"
#include "ddl/core/types.h"
#include "ddl/map/map.h"

namespace ddl::viewer {

/// What the map panel draws, copied out of the map at one instant.
struct MapSnapshot {
  std::vector<Vec3d> points_w;                        // live map points
  std::vector<SE3> keyframes_T_w_c;                   // live keyframes, by id
  std::vector<std::pair<Vec3d, Vec3d>> tree_edges_w;  // keyframe centre -> its parent's centre
};

MapSnapshot snapshot_map(const map::Map& map);

/// The virtual view camera: a pinhole of `width` x `height` pixels with focal length `focal_px`
/// and principal point at the centre, at pose T_v_w.
struct MapView {
  int width = 640;
  int height = 508;
  double focal_px = 420.0;
  SE3 T_v_w;
};

/// T_v_w of a camera at `eye_w` looking at `target_w`, with `down_w` pointing down in the image.
/// Throws std::invalid_argument when eye and target coincide or the view direction is parallel
/// to `down_w`.
SE3 look_at(const Vec3d& eye_w, const Vec3d& target_w, const Vec3d& down_w);

/// The view that follows the camera T_w_c: its eye `back_m` behind and `up_m` above the camera
/// (in the camera's own axes, ORB-SLAM2's ViewpointZ / ViewpointY), looking at the camera centre,
/// the camera's own down axis down.
SE3 follow_view(const SE3& T_w_c, double back_m, double up_m);

/// Renders the panel: dark background, points light grey, keyframes blue, spanning tree green,
/// the current camera (when given) red. Geometry behind the view camera is clipped at its near
/// plane. Throws std::invalid_argument for a non-positive size or focal length.
cv::Mat draw_map(const MapSnapshot& map, const std::optional<SE3>& current_T_w_c,
                 const MapView& view);

}  // namespace ddl::viewer
