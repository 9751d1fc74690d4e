#pragma once
// Short-term memory of the dynamic surfaces the CNN found, in the world frame. The CNN misses
// people it sees only in part where the image border cuts them (on syn_sitting_halfsphere the
// frames with under 2000 person pixels scored a mean IoU of 0.14). Such frames mostly follow or
// precede frames where the same person was in full view, and a sitting person, or one walking at
// 1 m/s for a third of a second, is still close to where that frame saw them.
//
// remember() keeps a subsample of the pixels of an inferred CNN mask (eroded first, so its spill
// onto the background is not kept), back-projected with their depth at the frame's tracked pose,
// with their colour, except the points a recent keyframe saw unmasked as static surface (the
// static veto: spill onto the floor at a person's feet). recall() projects what was remembered
// during the last max_age_frames frames into a new frame at its pose estimate; a point that lands
// within recall_band_px of the image border, where its colour is still seen, marks the pixels
// around it whose measured depth agrees (within tolerance_at(z)). A person still (partly) there
// is marked; where the person has gone, the background behind is farther away, or, right behind
// them, of other colours. Only CNN detections are remembered, never recalled pixels, so a false
// detection lives at most max_age_frames frames. docs/dynamics.md, "Dynamic memory", has the
// measurements.
// Not thread-safe: one instance per tracking thread.

#include <cstddef>
#include <cstdint>
#include <deque>
#include <opencv2/core.hpp>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"

namespace ddl::dynamics {

struct DynamicMemoryConfig {
  bool enabled = true;       // false = the CNN and geometry masks only
  int max_age_frames = 60;   // forget what was seen this many frames ago
  int sample_stride_px = 4;  // remember one mask pixel per stride x stride cell
  /// The CNN mask is eroded by this much before it is remembered: its upsampled edge spills onto
  /// the background next to a person, and remembered background would be re-marked as long as it
  /// is remembered (static, so its depth always agrees).
  int erode_px = 4;
  double depth_tolerance_m = 0.15;          // agreement at z = 0 (people move meanwhile)
  double depth_tolerance_quadratic = 0.01;  // grows by this times z^2, like the depth noise
  double min_depth_m = 0.3;                 // ignore depths closer than this
  double max_depth_m = 6.0;                 // and farther than this
  int max_splat_radius_px = 8;              // cap of the square a remembered point covers
  /// Colour test: a remembered point marks pixels only when a pixel within 1 px of where it
  /// projects has its colour (sum of |B|, |G|, |R| differences at most this). A person who stood
  /// right in front of a bookshelf leaves the shelf at the remembered depth, but not in the
  /// remembered colours. Negative = no colour test.
  int colour_tolerance = 60;
  /// Recall only where remembered points fall within this many pixels of the image border,
  /// where the CNN misses people cut by it; farther in, the CNN sees the whole person and is
  /// trusted (recalling there too marked shelves and desks that people had stood against).
  /// 0 = recall everywhere.
  int recall_band_px = 64;
  /// Whether tracking drops the features in the recalled mask too (like the geometry mask's).
  /// Otherwise their features are tracked and may become map points like any other; the recalled
  /// mask only joins the combined mask (dense mapping, inpainting, outputs).
  bool drop_features = false;
  /// Static veto: a point to remember is dropped when one of the last static_views keyframes
  /// saw it as part of a static surface: outside its dynamic mask, at a depth that agrees. That
  /// is CNN spill onto the floor at a person's feet or onto a shelf behind them, which erosion
  /// and depth do not remove and which would otherwise be re-marked for max_age_frames. 0 = no
  /// veto.
  int static_views = 5;
  /// Whether the memory remembers the CNN mask as the free-space votes judged it (its regions
  /// that the keyframes saw as static surface left out, as in the combined mask) rather than the
  /// network's whole mask: a false detection the votes reject is then not carried on for
  /// max_age_frames (composite combined IoU +0.006 over four starts; docs/dynamics.md).
  bool remember_judged = true;

  double tolerance_at(double z) const {
    return depth_tolerance_m + depth_tolerance_quadratic * z * z;
  }

  /// Throws ddl::ConfigError naming "dynamic.memory.<field>".
  void validate() const;
};

struct DynamicMemoryStats {
  int points_projected = 0;        // remembered points in front of the camera and in the image
  int points_colour_rejected = 0;  // of those, the ones whose colour is not there any more
  int pixels_marked = 0;
};

class DynamicMemory {
 public:
  DynamicMemory(const DynamicMemoryConfig& config, const camera::PinholeCamera& camera);

  /// Remembers the surface under `mask` (CV_8UC1, non-zero = dynamic class) of frame
  /// `frame_index`, seen at pose T_w_c with depth `depth_m` (CV_32FC1 metres, 0 = none) and
  /// colours `bgr` (CV_8UC3; empty = no colour test for these points).
  void remember(std::size_t frame_index, const SE3& T_w_c, const cv::Mat& mask,
                const cv::Mat& depth_m, const cv::Mat& bgr);

  /// Pixels of frame `frame_index` (pose estimate T_c_w, depth `depth_m`, colours `bgr`, which
  /// may be empty) where a surface remembered during the last max_age_frames frames still is:
  /// CV_8UC1 255 = dynamic, empty when nothing is remembered.
  cv::Mat recall(std::size_t frame_index, const SE3& T_c_w, const cv::Mat& depth_m,
                 const cv::Mat& bgr, DynamicMemoryStats* stats = nullptr);

  /// A keyframe for the static veto: its pose, depth and combined dynamic mask (CV_8UC1,
  /// non-zero = dynamic; may be empty). The last config.static_views are kept.
  void add_static_view(const SE3& T_w_c, const cv::Mat& depth_m, const cv::Mat& dynamic_mask);

  /// Moves what is kept in the world frame (remembered points, static-view poses) by the rigid
  /// motion T_new_old that a loop correction or global-BA merge gave the keyframes around the
  /// camera (pipeline::MapCorrectionFollower), so that recall() at poses in the corrected map
  /// finds the remembered surfaces where they were seen.
  void move_world(const SE3& T_new_old);

  /// Forgets everything (map reset: the old poses mean nothing any more).
  void clear() {
    snapshots_.clear();
    static_views_.clear();
  }

  std::size_t remembered_points() const;

 private:
  struct Point {
    float x, y, z;  // world frame
    float reach_m;  // half the sample spacing where it was seen
    std::uint8_t b, g, r;
    bool has_colour;
  };
  struct Snapshot {
    std::size_t frame_index = 0;
    std::vector<Point> points;
  };
  struct StaticView {
    SE3 T_c_w;
    cv::Mat depth_m;
    cv::Mat dynamic_mask;
  };
  void forget_before(std::size_t frame_index);
  /// Whether a static view saw the world point p_w as static surface (the static veto).
  bool seen_as_static(const Vec3d& p_w) const;
  /// Whether a pixel within 1 px of (u0, v0) has the point's colour (true without colours).
  bool colour_still_there(const Point& point, int u0, int v0, const cv::Mat& bgr) const;

  DynamicMemoryConfig config_;
  camera::PinholeCamera camera_;
  std::deque<Snapshot> snapshots_;       // oldest first
  std::deque<StaticView> static_views_;  // oldest first
};

}  // namespace ddl::dynamics
