#pragma once
// Reader interface so that datasets plug in behind one factory (io/dataset_factory.h).
// A reader validates its index files on construction (throwing ddl::InputError naming file and
// line) and loads images lazily in frame(); frame() throws ddl::InputError for a missing or
// unreadable image, 8-bit or wrongly sized depth, or RGB/depth size mismatch.
// Thread-safety: frame() is const and may be called from any thread.

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/io/rgbd_frame.h"

namespace ddl::io {

class DatasetReader {
 public:
  virtual ~DatasetReader() = default;
  /// Number of associated RGB-D frames.
  virtual std::size_t size() const = 0;
  /// RGB timestamp of frame i without loading images.
  virtual double timestamp(std::size_t i) const = 0;
  /// Loads, converts (depth to metres) and undistorts frame i.
  virtual RgbdFrame frame(std::size_t i) const = 0;
  /// The camera of the frames that frame() returns (undistorted).
  virtual const camera::PinholeCamera& camera() const = 0;
  /// A single-channel image in the stored images' pixel grid (a precomputed mask made for an
  /// RGB file) moved onto the grid of the frames frame() returns, nearest neighbour. Identity
  /// for datasets stored without distortion.
  virtual cv::Mat undistort_mask(const cv::Mat& stored) const { return stored; }
  /// CV_8UC1 in the frames' grid: 255 where a pixel comes from the stored image, 0 in the blank
  /// margin that undistortion leaves (camera::Undistorter::source_area). Empty when every pixel
  /// comes from the stored image.
  virtual cv::Mat source_area() const { return {}; }
  /// Path of the ground-truth trajectory (TUM format) when the dataset has one.
  virtual std::optional<std::string> groundtruth_path() const = 0;
  /// Short dataset name for logs and summaries (e.g. "rgbd_dataset_freiburg1_rpy").
  virtual std::string name() const = 0;
};

}  // namespace ddl::io
