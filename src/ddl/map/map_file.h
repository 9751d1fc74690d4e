#pragma once
// The sparse map on disk: keyframes (pose, features, spanning-tree parent, loop edges) and map
// points (position, observations, match statistics), so that a later run can relocalize in a map
// built before (localization mode) or extend it (docs/map-files.md has the layout and the use).
//
// What is not stored is rebuilt on load: the feature grid and scale pyramid of each keyframe, the
// covisibility graph (KeyFrame::update_connections from the observations), each point's
// descriptor, normal and distance range; the bags of words need the vocabulary and are computed
// by the caller (pipeline::System::load_map). The keyframes' depth images and dynamic masks are
// stored when the caller has them (KeyFrameImagesFn), and so are the dense stage's scans
// (DenseScan), from which a later run rebuilds the octree; the octree itself is not.
//
// Layout (little-endian, version 2; version 1 files, without dense scans, are read too): a 96-byte
// header, the keyframes and points in id order, the dense scans, zero padding to a multiple of 8
// bytes, and a u64 checksum of every preceding byte
// (core/binary_file.h). Loading checks the magic, version, size, checksum and every index and id
// it reads, and names the file and the record at fault.
// Pure functions of their inputs; save reads the map through its thread-safe accessors.

#include <cstdint>
#include <functional>
#include <map>
#include <opencv2/core.hpp>
#include <optional>
#include <string>
#include <vector>

#include "ddl/core/se3.h"
#include "ddl/map/map.h"

namespace ddl::map {

/// What a map can be used with, recorded beside it and checked by the loader's caller.
struct MapFileInfo {
  int image_width = 0;  // the undistorted camera of the keyframes' features
  int image_height = 0;
  double fx = 0.0, fy = 0.0, cx = 0.0, cy = 0.0;
  std::uint64_t descriptor_tag = 0;    // vocabulary::descriptor_fingerprint of the BRIEF pattern
  std::uint64_t vocabulary_words = 0;  // word count of the vocabulary the map was built with
};

/// A keyframe's images stored beside it (the references of the multi-view geometry check).
struct KeyFrameImages {
  cv::Mat depth_m;       // CV_32FC1 metres, 0 = none; stored at 1/5000 m (TUM's 16-bit PNG)
  cv::Mat dynamic_mask;  // CV_8UC1, non-zero = dynamic; empty = nothing marked
};
/// The images of a keyframe to store, or none.
using KeyFrameImagesFn = std::function<std::optional<KeyFrameImages>(KeyFrameId)>;

/// One keyframe's contribution to the dense map (the octree), as the dense stage keeps it: its
/// repaired colour and depth and the pixels not to map, at the octree's pixel stride. A scan is
/// anchored to a keyframe of the file by a relative pose, so that the scans of keyframes culled
/// during the run (not in the file) are kept too, and all of them follow when a later run moves
/// the anchors (local BA, loop closure).
struct DenseScan {
  KeyFrameId anchor = 0;
  SE3 T_anchor_c;      // the scan's camera in the anchor keyframe's camera frame
  int pixel_step = 1;  // the images hold every pixel_step-th camera pixel in u and v
  cv::Mat bgr;         // CV_8UC3
  cv::Mat depth_m;     // CV_32FC1 metres, 0 = none; stored at 1/5000 m
  cv::Mat exclude;     // CV_8UC1, non-zero = not mapped; empty = nothing excluded
};

/// What load_map_file() read.
struct MapFileContents {
  MapFileInfo info;
  std::uint32_t version = 0;
  std::size_t keyframes = 0;
  std::size_t map_points = 0;
  std::map<KeyFrameId, KeyFrameImages> images;  // of the keyframes stored with images
  std::vector<DenseScan> dense_scans;           // version 2; anchors are keyframes of the file
};

/// Writes the good keyframes and points of `map`, whole or not at all (write_file_atomically:
/// through `<path>.partial` and a rename; the folder is created). Observations of keyframes that
/// are not stored are left out. Throws ddl::OutputError naming the file when it cannot be written.
/// `images`, when given, supplies the keyframes' depth images and masks (each a 16-bit and an
/// 8-bit PNG in the file; a keyframe without is stored without). `dense_scans` are stored when
/// their anchor is a stored keyframe (the others are left out); ddl::Error when one is malformed
/// (images of the wrong type, or of a size other than the camera's at its pixel step).
void save_map_file(const Map& map, const MapFileInfo& info, const std::string& path,
                   const KeyFrameImagesFn& images = {},
                   const std::vector<DenseScan>& dense_scans = {});

/// Fills `map`, which must be empty and never have held anything (ddl::Error otherwise), with
/// the file's keyframes and points and raises its id counters past theirs. The first keyframe of
/// the file becomes the map's origin. Throws ddl::InputError naming the file (and the record)
/// when it is not a readable map file of this version or is corrupted. `accept`, when given, sees
/// the header before anything is added to `map` and throws to refuse the file (a map of another
/// camera or vocabulary).
MapFileContents load_map_file(const std::string& path, Map& map,
                              const std::function<void(const MapFileInfo&)>& accept = {});

}  // namespace ddl::map
