#pragma once
// The tracking frame: the features of one RGB-D image (map::FrameFeatures: ORB keypoints outside
// the dynamic mask, descriptors, depth and virtual right coordinate per keypoint, grid), the pose
// being estimated, and one map point slot and outlier flag per keypoint (ORB-SLAM2 Frame,
// section III-A and IV of the T-RO 2017 paper).
//
// Frames: T_c_w maps world coordinates into this camera; pixels are undistorted (io delivers
// undistorted images), (0, 0) the centre of the top-left pixel.
// Threads: a Frame belongs to the tracking thread. Its features become shared (const) once a
// keyframe is made from it; compute_bow() must be called before that.

#include <cstdint>
#include <memory>
#include <opencv2/core.hpp>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"
#include "ddl/features/orb_extractor.h"
#include "ddl/io/rgbd_frame.h"
#include "ddl/map/frame_features.h"
#include "ddl/map/keyframe.h"
#include "ddl/map/map_point.h"
#include "ddl/tracking/tracker_config.h"
#include "ddl/vocabulary/vocabulary.h"

namespace ddl::tracking {

using FrameId = std::uint64_t;

/// Camera model and depth conventions shared by all frames of a run (undistorted pinhole).
struct FrameGeometry {
  int width = 0;
  int height = 0;
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  double bf = 0.0;             // virtual baseline times fx [m px]
  double baseline_m = 0.0;     // bf / fx
  double close_depth_m = 0.0;  // ORB-SLAM2 ThDepth: depth below which a point is "close"
  double min_depth_m = 0.0;    // valid depth range (exclusive min, inclusive max)
  double max_depth_m = 0.0;
  int depth_edge_radius_px = 0;   // keypoints this close to a depth edge get no depth (0 = off)
  double depth_edge_ratio = 0.0;  // an edge: a reading off the keypoint's by this share of it

  /// Undistorted geometry of `camera` (its distortion is ignored: images arrive undistorted).
  static FrameGeometry from(const camera::PinholeCamera& camera, const FrameConfig& config);

  /// Pixel of a camera-frame point (z > 0 required by the caller).
  Vec2d project(const Vec3d& p_c) const {
    return {fx * p_c.x() / p_c.z() + cx, fy * p_c.y() / p_c.z() + cy};
  }
  /// Inside the image: 0 <= u < width, 0 <= v < height.
  bool in_image(double u, double v) const {
    return u >= 0.0 && v >= 0.0 && u < width && v < height;
  }
};

class Frame {
 public:
  Frame() = default;
  Frame(FrameId id, double timestamp_s, std::shared_ptr<map::FrameFeatures> features,
        std::shared_ptr<const FrameGeometry> geometry);

  FrameId id() const { return id_; }
  double timestamp_s() const { return timestamp_s_; }
  bool valid() const { return features_ != nullptr; }
  const map::FrameFeatures& features() const { return *features_; }
  std::shared_ptr<const map::FrameFeatures> features_ptr() const { return features_; }
  const FrameGeometry& geometry() const { return *geometry_; }
  std::size_t size() const { return features_ ? features_->size() : 0; }

  // --- pose ----------------------------------------------------------------------------------
  bool has_pose() const { return has_pose_; }
  const SE3& T_c_w() const { return T_c_w_; }
  SE3 T_w_c() const { return T_c_w_.inverse(); }
  const Vec3d& camera_center_w() const { return center_w_; }
  void set_T_c_w(const SE3& T_c_w);

  // --- map point slots -----------------------------------------------------------------------
  const map::MapPointPtr& map_point(std::size_t i) const { return map_points_[i]; }
  const std::vector<map::MapPointPtr>& map_points() const { return map_points_; }
  void set_map_point(std::size_t i, map::MapPointPtr point);
  /// Clears slot i and its outlier flag.
  void clear_map_point(std::size_t i);
  void clear_map_points();
  /// Replaces all slots (size must equal size()); outlier flags are reset.
  void set_map_points(std::vector<map::MapPointPtr> points);
  bool is_outlier(std::size_t i) const { return outliers_[i] != 0; }
  void set_outlier(std::size_t i, bool outlier) { outliers_[i] = outlier ? 1 : 0; }
  /// Number of occupied slots.
  int matched_count() const;

  /// Map points rejected as outliers by this frame's pose estimation: local-map search does not
  /// project them again into this frame (ORB-SLAM2 marks them "last seen" by the frame).
  const std::vector<map::MapPointId>& rejected_points() const { return rejected_points_; }
  void add_rejected_point(map::MapPointId id) { rejected_points_.push_back(id); }
  void clear_rejected_points() { rejected_points_.clear(); }

  // --- depth -----------------------------------------------------------------------------------
  bool has_depth(std::size_t i) const { return features_->depth_m[i] > 0.0f; }
  /// Depth measured and below FrameGeometry::close_depth_m.
  bool is_close(std::size_t i) const {
    const float d = features_->depth_m[i];
    return d > 0.0f && d < geometry_->close_depth_m;
  }
  /// World point of keypoint i from its depth (precondition: has_depth(i) and has_pose()).
  Vec3d unproject_w(std::size_t i) const;

  // --- dynamic content -------------------------------------------------------------------------
  /// Removes the keypoints at non-zero pixels of `mask` (CV_8UC1 of the image size; empty = no-op)
  /// with their descriptors, depth, map point slots and outlier flags, rebuilds the grid and drops
  /// a computed BoW vector (its feature indices would be stale). DDL-SLAM Algorithm 1: features
  /// the multi-view geometry check found on moving content are not used after the low-cost pose.
  /// Must not be called after the features were shared with a keyframe. Returns how many were
  /// removed.
  std::size_t drop_features_in(const cv::Mat& mask);

  // --- bag of words ----------------------------------------------------------------------------
  bool has_bow() const { return features_->has_bow(); }
  /// Computes the BoW vector and direct index once (no-op when present). Must not be called after
  /// the features were shared with a keyframe.
  void compute_bow(const vocabulary::Vocabulary& vocabulary, int levels_up);

  // --- reference keyframe ----------------------------------------------------------------------
  const map::KeyFramePtr& reference_keyframe() const { return reference_keyframe_; }
  void set_reference_keyframe(map::KeyFramePtr keyframe) {
    reference_keyframe_ = std::move(keyframe);
  }

 private:
  FrameId id_ = 0;
  double timestamp_s_ = 0.0;
  std::shared_ptr<map::FrameFeatures> features_;
  std::shared_ptr<const FrameGeometry> geometry_;
  bool has_pose_ = false;
  SE3 T_c_w_;
  Vec3d center_w_ = Vec3d::Zero();
  std::vector<map::MapPointPtr> map_points_;
  std::vector<std::uint8_t> outliers_;
  std::vector<map::MapPointId> rejected_points_;
  map::KeyFramePtr reference_keyframe_;
};

/// Builds frames: grayscale conversion, ORB extraction outside the dynamic mask, depth per
/// keypoint, virtual right coordinate, grid. Holds the extractor's scratch buffers, so one
/// builder serves one thread.
class FrameBuilder {
 public:
  /// Throws ddl::ConfigError for an invalid camera or config.
  FrameBuilder(const camera::PinholeCamera& camera, const features::OrbExtractorConfig& orb,
               const FrameConfig& config);

  /// `frame.rgb` CV_8UC3 (BGR) or CV_8UC1, `frame.depth_m` CV_32FC1 of the camera's size;
  /// `dynamic_mask` empty or CV_8UC1 of that size (non-zero = no features there). Throws
  /// ddl::InputError naming the image file when an image has the wrong type or size.
  Frame build(const io::RgbdFrame& frame, const cv::Mat& dynamic_mask, FrameId id);

  const std::shared_ptr<const FrameGeometry>& geometry() const { return geometry_; }
  const features::ScalePyramid& scale_pyramid() const { return extractor_.scale_pyramid(); }
  const features::BriefPattern& brief_pattern() const { return extractor_.pattern(); }

 private:
  std::shared_ptr<const FrameGeometry> geometry_;
  features::OrbExtractor extractor_;
  cv::Mat gray_;
};

/// The depth used for keypoint (u, v): the reading at the nearest pixel, or 0 when it is outside
/// the valid range (or the pixel outside the image), or when depth_edge_radius_px > 0 and a valid
/// reading within that many pixels differs from it by more than depth_edge_ratio of it.
float keypoint_depth(const cv::Mat& depth_m, float u, float v, const FrameGeometry& geometry);

}  // namespace ddl::tracking
