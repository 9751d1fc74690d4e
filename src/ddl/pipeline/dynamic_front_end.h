#pragma once
// The dynamic-content front end (DDL-SLAM sections III-B to III-D, Algorithm 1): the CNN mask of
// a-priori dynamic classes, the multi-view geometry mask against reference keyframes at a
// low-cost pose, their union, and the exclusion mask handed to ORB extraction (the union grown by
// a border, so features on object edges are not used either).
// Thread-safety: one instance per pipeline; cnn_mask() may run on a segmentation thread
// (SegmentationStage) while the other methods run on the tracking thread (they share no state but
// the keyframe depth cache, which is locked); cnn_mask() itself from one thread at a time.

#include <functional>
#include <map>
#include <memory>
#include <mutex>
#include <opencv2/core.hpp>
#include <optional>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/core/se3.h"
#include "ddl/dynamics/dynamic_memory.h"
#include "ddl/dynamics/free_space_check.h"
#include "ddl/dynamics/geometry_check.h"
#include "ddl/dynamics/mask_edge_refinement.h"
#include "ddl/io/rgbd_frame.h"
#include "ddl/map/keyframe.h"
#include "ddl/map/map_file.h"
#include "ddl/pipeline/system_config.h"
#include "ddl/segmentation/segmenter.h"

namespace ddl::pipeline {

/// The CNN mask of one frame, computed inline or ahead of tracking (SegmentationStage).
struct CnnMask {
  cv::Mat mask;             // CV_8UC1 255 = dynamic class (empty when segmentation is off)
  double elapsed_ms = 0.0;  // inference and post-processing
  bool reused = false;      // the last CNN mask grown (dynamic.segmentation_interval), no inference
  bool turned = false;      // the frame was turned upright for the CNN (segmentation.upright)
  int pictures_dropped = 0;   // regions dropped as pictures (dynamic.picture_veto)
  int pictures_unjudged = 0;  // regions kept unjudged (picture_veto.max_flood_pixels spent)
};

struct DynamicMasks {
  cv::Mat cnn;         // CV_8UC1 255 = dynamic class (empty when segmentation is off)
  cv::Mat geometry;    // CV_8UC1 255 = moved according to the geometry check (may be empty)
  cv::Mat memory;      // CV_8UC1 255 = where a recent CNN detection still is (may be empty)
  cv::Mat free_space;  // CV_8UC1 255 = in space earlier keyframes saw empty (may be empty)
  /// The free-space regions before their growth over the depth (free_space.grow_step_m; the same
  /// as free_space without growth): where tracking drops features unless
  /// free_space.grow_drops_features.
  cv::Mat free_space_regions;
  /// cnn with the regions the free-space votes saw as static left out (cnn itself when the check
  /// did not run): the CNN's part of the combined mask
  cv::Mat cnn_kept;
  /// The union of the four, the regions of the CNN and memory masks (and, with
  /// free_space.judge_geometry, of the geometry mask) that the free-space votes saw as static
  /// left out (empty when all are), snapped to the colour edges with dynamic.edge_refinement.
  /// What the keyframe keeps (the memory's static veto, the geometry check's references, the map
  /// file), the dense map and the outputs take.
  cv::Mat combined;
  /// The union of the four before the judging: what the keyframe's free-space view counts as
  /// masked. Judged regions would otherwise feed back: dropped in one keyframe, they become its
  /// static votes, and the next judging drops more (a person sitting still vanished).
  cv::Mat flagged;
  cv::Mat exclusion;  // the sources' masks (unjudged, unrefined) grown by feature_border_px:
                      // features there are not used (CNN part before ORB extraction, the
                      // others after the low-cost pose)
  dynamics::GeometryCheckStats geometry_stats;
  dynamics::DynamicMemoryStats memory_stats;
  dynamics::FreeSpaceVotes free_space_votes;  // empty grids when the check did not run
  dynamics::FreeSpaceStats free_space_stats;
  double segmentation_ms = 0.0;
  double geometry_ms = 0.0;
  bool refined = false;        // the combined mask was refined (dynamic.edge_refinement)
  double refinement_ms = 0.0;  // how long that took
};

class DynamicFrontEnd {
 public:
  /// Creates the segmenter. A missing model file with fallback_without_model gives a warning
  /// and geometry-only operation; an invalid model file throws ddl::InputError.
  DynamicFrontEnd(const DynamicConfig& config, const camera::PinholeCamera& camera,
                  const std::string& shared_dir);

  bool enabled() const { return config_.enabled; }
  bool has_segmenter() const { return segmenter_ != nullptr; }
  std::string segmenter_description() const;

  /// Moves a mask of the folder backend (made for the stored RGB file) onto the frames' pixel
  /// grid (io::DatasetReader::undistort_mask). Call before the first cnn_mask(); without it the
  /// masks are used as read.
  void set_stored_mask_mapping(std::function<cv::Mat(const cv::Mat&)> mapping) {
    stored_mask_mapping_ = std::move(mapping);
  }
  /// Where the frames' pixels come from the sensor's image (io::DatasetReader::source_area; empty
  /// = everywhere). The picture veto does not take the blank margin undistortion leaves for a
  /// depth hole beside a region. Call before the first cnn_mask().
  void set_source_area(const cv::Mat& area) { source_area_ = area; }
  const cv::Mat& source_area() const { return source_area_; }

  /// CNN mask of one frame (empty when segmentation is off); frames in index order. With
  /// dynamic.segmentation_interval > 1 most frames of the ONNX backend reuse the last inferred
  /// mask, grown (the schedule saves CNN time; the folder backend reads every frame's mask).
  /// A frame whose up direction (RgbdFrame::up_c) shows a roll of at least
  /// segmentation.upright_min_roll_deg is turned upright for the network (segmentation/upright.h).
  CnnMask cnn_mask(const io::RgbdFrame& frame);

  /// What the geometry check needs of the reference keyframes (best overlap first, at most
  /// dynamic.geometry.max_reference_keyframes): pose, keypoints with depth, cached depth image
  /// and mask. Their poses are read here: call it where they are consistent with each other and
  /// with the frame's pose (System reads them under Map::read_consistent).
  std::vector<dynamics::ReferenceView> reference_views(
      const std::vector<map::KeyFramePtr>& references) const;

  /// Geometry mask at pose T_c_w against `references` (from reference_views()); the previous
  /// frame's pose, when known, sizes the seed windows to the camera motion.
  cv::Mat geometry_mask(const io::RgbdFrame& frame, const SE3& T_c_w,
                        const std::vector<dynamics::ReferenceView>& references,
                        dynamics::GeometryCheckStats* stats,
                        const std::optional<SE3>& T_c_w_previous = std::nullopt) const;

  /// The keyframes that vote in the free-space check of the frame at pose T_c_w: the cached ones
  /// at least free_space.min_reference_age_s older than it and not culled, with their current
  /// poses (dynamics::select_free_space_views). Call it where the poses are consistent with each
  /// other and with the frame's (System reads them under Map::read_consistent).
  std::vector<dynamics::FreeSpaceView> free_space_views(const io::RgbdFrame& frame,
                                                        const SE3& T_c_w) const;

  /// The free-space mask of the frame at pose T_c_w against `views`; the votes go to `votes`
  /// (for finish_masks), the regions before their growth to `ungrown` (optional). Empty when the
  /// check is off or has no view.
  cv::Mat free_space_mask(const io::RgbdFrame& frame, const SE3& T_c_w,
                          const std::vector<dynamics::FreeSpaceView>& views,
                          dynamics::FreeSpaceVotes* votes, dynamics::FreeSpaceStats* stats,
                          cv::Mat* ungrown = nullptr) const;

  /// `mask` grown by feature_border_px: where features are not used (empty stays empty).
  cv::Mat exclusion_mask(const cv::Mat& mask) const;

  /// Whether recent CNN detections are remembered (dynamic.memory.enabled with a segmenter).
  bool memory_enabled() const;

  /// Pixels of the frame at pose T_c_w where a dynamic surface found by the CNN in the last
  /// dynamic.memory.max_age_frames frames still is (dynamics::DynamicMemory; empty when off).
  cv::Mat memory_mask(const io::RgbdFrame& frame, const SE3& T_c_w,
                      dynamics::DynamicMemoryStats* stats);

  /// Remembers the frame's CNN mask (masks.cnn_kept with memory.remember_judged, else masks.cnn)
  /// at its tracked pose T_w_c; a reused mask is not remembered.
  void remember_cnn_mask(const io::RgbdFrame& frame, const SE3& T_w_c, const DynamicMasks& masks,
                         bool reused);

  /// Moves the remembered detections with a loop correction or global-BA merge (T_w_new_w_old,
  /// from MapCorrectionFollower).
  void move_dynamic_surfaces(const SE3& T_new_old) { memory_.move_world(T_new_old); }

  /// Forgets the remembered detections (map reset).
  void forget_dynamic_surfaces() { memory_.clear(); }

  /// The combined mask (DynamicMasks::combined: the union of the four sources, the regions the
  /// free-space votes saw as static left out), and the exclusion mask as the union of the
  /// CNN exclusion and `moved_exclusion` (the geometry and memory masks grown by the border;
  /// dilation distributes over union, so this is the union grown by the border). With
  /// dynamic.edge_refinement the combined mask is then snapped to the colour edges of `bgr` (the
  /// frame's image; empty = not refined); the exclusion mask is not.
  void finish_masks(DynamicMasks& masks, const cv::Mat& bgr, const cv::Mat& cnn_exclusion,
                    const cv::Mat& moved_exclusion) const;

  /// Keeps the keyframe's depth image for later multi-view checks (bounded cache).
  /// With the dynamic memory on, also its static veto view (`dynamic_mask`: the combined mask).
  /// The free-space view takes `flagged_mask` (DynamicMasks::flagged) when given, else
  /// `dynamic_mask`.
  void remember_keyframe(const map::KeyFramePtr& keyframe, const cv::Mat& depth_m,
                         const cv::Mat& dynamic_mask, const cv::Mat& flagged_mask = cv::Mat());
  /// remember_keyframe for a keyframe of a map loaded from a file: its free-space view counts
  /// the stored (combined) mask as masked, and it votes whatever its timestamp (the age rule,
  /// free_space.min_reference_age_s, compares stamps of one session).
  void remember_loaded_keyframe(const map::KeyFramePtr& keyframe, const cv::Mat& depth_m,
                                const cv::Mat& dynamic_mask);
  /// Forgets the cached images of the keyframes with ids below `first_kept` (map reset: those
  /// keyframes are in a world frame that is gone, although they may still be alive).
  void forget_keyframes_before(map::KeyFrameId first_kept);
  /// The cached depth image and mask of a keyframe (for the map file), if the cache holds it.
  std::optional<map::KeyFrameImages> keyframe_images(map::KeyFrameId id) const;

 private:
  /// The turn that makes `frame` upright for the CNN, when one is configured and needed.
  std::optional<double> upright_turn(const io::RgbdFrame& frame) const;
  void keep_keyframe(const map::KeyFramePtr& keyframe, const cv::Mat& depth_m,
                     const cv::Mat& dynamic_mask, const cv::Mat& flagged_mask, bool loaded);

  DynamicConfig config_;
  camera::PinholeCamera camera_;
  std::unique_ptr<segmentation::Segmenter> segmenter_;
  cv::Mat last_cnn_mask_;  // cnn_mask()'s thread only
  std::optional<std::size_t> last_cnn_index_;
  mutable std::mutex cache_mutex_;
  std::function<cv::Mat(const cv::Mat&)> stored_mask_mapping_;
  cv::Mat source_area_;  // see set_source_area
  struct KeyframeImages {
    std::weak_ptr<map::KeyFrame> keyframe;  // culled or gone: the first to leave the cache
    cv::Mat depth_m;
    cv::Mat dynamic_mask;                // empty when the mask marked nothing
    dynamics::FreeSpaceView free_space;  // its images prepared once (pose set when it votes)
    bool loaded = false;                 // from a map file (remember_loaded_keyframe)
  };
  std::map<map::KeyFrameId, KeyframeImages> depth_cache_;  // for the multi-view checks
  dynamics::DynamicMemory memory_;                         // tracking thread only
};

}  // namespace ddl::pipeline
