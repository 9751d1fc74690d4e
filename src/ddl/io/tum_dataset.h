#pragma once
// Reader for RGB-D sequences in the TUM RGB-D benchmark layout (also used by the Bonn RGB-D
// Dynamic dataset and by our synthetic sequences):
//
//   <dir>/rgb.txt, <dir>/depth.txt     `timestamp path` per line, '#' comments, paths relative to
//                                      <dir>; any image format OpenCV decodes (PNG, JPEG, ...)
//   <dir>/associations.txt (optional)  `rgb_timestamp rgb_path depth_timestamp depth_path`
//   <dir>/groundtruth.txt (optional)   `timestamp tx ty tz qx qy qz qw` (io::read_tum_trajectory)
//   <dir>/accelerometer.txt (optional) `timestamp ax ay az` (io::AccelerometerLog): with
//                                      SequenceOptions::read_accelerometer each frame gets the
//                                      direction up in its camera frame (RgbdFrame::up_c)
//
// RGB/depth pairs come from an associations file or are computed from rgb.txt and depth.txt
// exactly as TUM's associate.py does (io::associate, |t_rgb - t_depth| < max_difference_s).
// Images are 8-bit colour (grayscale is expanded to BGR) and 16-bit single-channel depth in raw
// units (depth_factor per metre, 0 = no measurement); frame() returns depth in metres (CV_32F,
// 0 stays 0) and both images undistorted with camera::Undistorter (depth by nearest neighbour).
//
// Threads: the constructor validates every index file and throws ddl::InputError naming the file
// and line (malformed line, non-numeric or non-increasing timestamp, empty list, no pairs).
// After construction the object is immutable: every const method, frame() included, may be
// called concurrently from any thread (e.g. a prefetching loader thread while the pipeline reads
// timestamps).

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

#include "ddl/camera/pinhole_camera.h"
#include "ddl/io/accelerometer.h"
#include "ddl/io/dataset_reader.h"
#include "ddl/io/rgbd_frame.h"

namespace ddl::io {

/// Where the RGB/depth pairs of a sequence come from.
enum class AssociationSource {
  kAuto,        // <dir>/associations.txt when present, else computed from the timestamps
  kFile,        // an associations file (SequenceOptions::associations_file or associations.txt)
  kTimestamps,  // always computed from rgb.txt and depth.txt (associate.py), ignoring any file
};

/// Parses "auto" | "file" | "timestamps"; throws ddl::ConfigError naming `key` otherwise.
AssociationSource parse_association_source(const std::string& text,
                                           const std::string& key = "dataset.associations");
std::string to_string(AssociationSource source);

/// Throws ddl::InputError naming `dir` when it does not exist ("sequence folder not found") or is
/// not a folder. Every reader and the bench check a sequence folder with it.
void require_sequence_folder(const std::string& dir);

/// The sequence name of a folder: its last path component ("rgbd_dataset_freiburg1_rpy" for
/// ".../rgbd_dataset_freiburg1_rpy/"), resolving "." and "..".
std::string sequence_name(const std::string& dir);

struct SequenceOptions {
  AssociationSource association = AssociationSource::kAuto;  // how RGB/depth pairs are found
  std::string associations_file;    // kFile: path as given (absolute or relative to the working
                                    // directory); empty means <dir>/associations.txt. Setting it
                                    // with kAuto also selects this file.
  double max_difference_s = 0.02;   // associate.py --max_difference, seconds (computed pairs)
  bool check_files_on_open = true;  // fail at construction when a listed image file is missing
                                    // (or no regular file)
  /// Read groundtruth.txt at construction, so that a malformed line stops a run before its first
  /// frame; off for a run that does not evaluate (it then does not depend on the file).
  bool check_groundtruth_on_open = true;
  /// Load <dir>/accelerometer.txt, when present, into each frame's up direction (RgbdFrame::up_c;
  /// a malformed file is then an error). Off, the file is not read: a run that does not use it
  /// does not depend on it.
  bool read_accelerometer = false;

  /// Throws ddl::ConfigError naming the key ("dataset.max_difference") when out of range.
  void validate() const;
};

/// One associated RGB-D pair as listed (paths resolved against the sequence folder).
struct FramePair {
  double rgb_timestamp_s = 0.0;
  std::string rgb_path;
  double depth_timestamp_s = 0.0;
  std::string depth_path;
};

class TumDataset : public DatasetReader {
 public:
  /// `camera` is the calibration of the images as stored (with distortion); it is validated.
  /// Throws ddl::InputError (files) or ddl::ConfigError (options, camera).
  TumDataset(const std::string& dir, const camera::PinholeCamera& camera,
             const SequenceOptions& options = {});

  std::size_t size() const override { return pairs_.size(); }
  double timestamp(std::size_t i) const override;
  RgbdFrame frame(std::size_t i) const override;
  /// The undistorted camera (what frame() returns).
  const camera::PinholeCamera& camera() const override { return camera_; }
  cv::Mat undistort_mask(const cv::Mat& stored) const override {
    return undistorter_.undistort_depth(stored);  // nearest neighbour, no new values
  }
  cv::Mat source_area() const override { return undistorter_.source_area(); }
  std::optional<std::string> groundtruth_path() const override { return groundtruth_path_; }
  /// The accelerometer log (<dir>/accelerometer.txt), when the sequence has one and
  /// SequenceOptions::read_accelerometer asked for it.
  const std::optional<AccelerometerLog>& accelerometer() const { return accelerometer_; }
  std::string name() const override { return name_; }

  /// The calibration of the stored images (with distortion), as given to the constructor.
  const camera::PinholeCamera& input_camera() const { return input_camera_; }
  const std::string& directory() const { return dir_; }
  /// All pairs, in increasing RGB timestamp order.
  const std::vector<FramePair>& pairs() const { return pairs_; }
  /// Human-readable origin of the pairs, e.g. "associations.txt" or "associate(rgb.txt,
  /// depth.txt, max_difference 0.02 s)".
  const std::string& association_description() const { return association_description_; }

 private:
  void read_association_file(const std::string& path);
  void associate_timestamps(double max_difference_s);

  std::string dir_;
  std::string name_;
  camera::PinholeCamera input_camera_;
  camera::PinholeCamera camera_;
  camera::Undistorter undistorter_;
  std::vector<FramePair> pairs_;
  std::optional<std::string> groundtruth_path_;
  std::optional<AccelerometerLog> accelerometer_;
  std::string association_description_;
};

}  // namespace ddl::io
