#pragma once
// Configuration of the whole system: one struct per stage, each with its own defaults and
// validate(). Read from YAML only by ddl::config (config/system_config.h), which also writes the
// effective configuration next to every run's outputs and generates docs/configuration.md.

#include <cstddef>
#include <string>

#include "ddl/dynamics/dynamic_memory.h"
#include "ddl/dynamics/free_space_check.h"
#include "ddl/dynamics/geometry_check.h"
#include "ddl/dynamics/mask_depth_trim.h"
#include "ddl/dynamics/mask_edge_refinement.h"
#include "ddl/dynamics/picture_veto.h"
#include "ddl/loop/loop_closer.h"
#include "ddl/mapping/local_mapper.h"
#include "ddl/pipeline/dense_mapper.h"
#include "ddl/segmentation/segmenter.h"
#include "ddl/tracking/tracker.h"

namespace ddl::pipeline {

enum class RunMode {
  kDeterministic,  // all stages inline, reproducible (tests, evaluation)
  kThreaded,       // segmentation, mapping, loop closing and dense mapping in their own threads
};

/// The dynamic-content front end (DDL-SLAM sections III-B to III-D).
struct DynamicConfig {
  bool enabled = true;           // false = the plain SLAM core (the paper's ORB-SLAM2 column)
  bool use_segmentation = true;  // CNN masks of a-priori dynamic classes
  /// The paper's sparse multi-view geometry check (Algorithm 1) against reference keyframes. Off
  /// by default: the free-space check (free_space) finds the people better (composite mean IoU
  /// 0.64 against 0.48, synthetic walking 0.88-0.89 against 0.79-0.85) but the moved box less
  /// well (recall 0.59-0.77 against 0.70-0.85); docs/dynamics.md, "Free-space check".
  /// config/ddl_slam_paper.yaml turns it on in place of the free-space check.
  bool use_geometry = false;
  int feature_border_px = 8;           // features this close to the mask are not used either
  bool fallback_without_model = true;  // missing model file: warn, run the multi-view checks only
  /// Real-time schedule (docs/dynamics.md): the CNN runs on a frame when at least this many
  /// frames passed since its last run; the frames between reuse that mask grown by
  /// segmentation_reuse_dilation_px. 1 = the CNN on every frame; 2 halves its cost for ~0.2 mm
  /// ATE on syn_walking_xyz.
  int segmentation_interval = 2;
  int segmentation_reuse_dilation_px = 8;  // growth of a reused CNN mask (people move meanwhile)
  /// Keyframe depth images (and dynamic masks) kept for the geometry check's references and the
  /// free-space check's views, culled keyframes dropped first, then the oldest: about 1.2 MB each
  /// at 640x480 (1.5 MB with a mask; 2.7 MB with the free-space check's window minimum).
  std::size_t keyframe_depth_cache = 200;
  segmentation::SegmenterConfig segmentation;
  dynamics::DepthTrimConfig depth_trim;      // CNN masks cut to their region's depth (spill)
  dynamics::PictureVetoConfig picture_veto;  // CNN regions standing in front of nothing dropped
  dynamics::GeometryCheckConfig geometry;
  dynamics::DynamicMemoryConfig memory;  // CNN detections of recent frames, re-projected
  dynamics::FreeSpaceConfig free_space;  // the frame's points against many earlier keyframes
  dynamics::EdgeRefinementConfig edge_refinement;  // the combined mask snapped to colour edges

  /// Whether keyframe depth images are kept (dynamic.keyframe_depth_cache): the references of the
  /// geometry check and the views of the free-space check.
  bool keeps_keyframe_images() const { return enabled && (use_geometry || free_space.enabled); }

  void validate() const;
};

struct SystemConfig {
  RunMode mode = RunMode::kDeterministic;   // see System
  std::size_t keyframe_queue_capacity = 4;  // tracking -> local mapping queue (threaded mode)
  /// Deterministic mode: local mapping runs inline, so it is never busy and tracking would insert
  /// a keyframe on almost every frame. To keep ORB-SLAM2's keyframe rate reproducibly, mapping
  /// reports itself busy for this many frames after each keyframe (about its processing time at
  /// 30 Hz). 0 = always idle.
  int deterministic_mapping_busy_frames = 4;
  /// Threaded mode: until tracking has created this many keyframes in the map (since it began
  /// or was reset), it waits before each frame until local mapping has processed every keyframe
  /// queued, as in deterministic mode. 30 removed the composite's occasional bad threaded starts
  /// (first 130 frames: 4 of 50 runs above 0.05 m without, none of 50 with it), but over the whole
  /// composite it cost 6% of the frame rate and its median ATE rose from 0.0219 to 0.0237 m (six
  /// runs each; docs/RESULTS.md, stop 32), so it is off by default. 0 = never wait.
  int threaded_lockstep_keyframes = 0;
  tracking::TrackerConfig tracking;  // includes ORB extraction (tracking.orb)
  mapping::LocalMapperConfig mapping;
  loop::LoopCloserConfig loop;
  DynamicConfig dynamic;
  DenseMapperConfig dense;
  std::string shared_dir = "../shared";  // where relative model paths are looked up
  std::string output_dir;                // where --save-masks / --save-inpainted write

  /// Depth images captured at another instant than their colour images (a camera with
  /// depth_time_offset_s, such as tum1) are moved to the colour image's instant after the
  /// low-cost pose, for the dynamic checks, keyframe views and the dense map; tracking keeps the
  /// depth as read (pipeline::DepthTimeAligner; docs/dynamics.md, "Depth in time"). On by
  /// default since stop 39, with tracking.frame.depth_edge_radius_px (without it the composite's
  /// start-frame-0 ATE rose from 0.0246 to 0.0381 m): the composite's combined mask IoU 0.628 ->
  /// 0.660 over four start frames. Cameras without the offset are never moved.
  bool align_depth_in_time = true;

  bool save_masks = false;  // write <output_dir>/masks/<stamp>.png (combined dynamic mask; parts in
                            // masks/cnn|geometry|memory|free_space/)

  /// Throws ddl::ConfigError naming the key.
  void validate() const;
};

}  // namespace ddl::pipeline
