#include "ddl/io/tum_dataset.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>
#include <stdexcept>
#include <unordered_map>
#include <vector>

#include "ddl/core/error.h"
#include "ddl/io/associate.h"
#include "ddl/io/text_table.h"
#include "ddl/io/trajectory_io.h"

namespace ddl::io {
namespace fs = std::filesystem;

namespace {

// One `timestamp path` list (rgb.txt or depth.txt), validated.
struct StampedFileList {
  std::vector<double> stamps;
  std::vector<std::string> paths;
};

std::string resolve(const std::string& dir, const std::string& relative) {
  const fs::path p(relative);
  return p.is_absolute() ? p.string() : (fs::path(dir) / p).string();
}

void require_increasing(const std::string& file, std::size_t line, double stamp,
                        const std::string& text, const std::vector<double>& previous) {
  if (!previous.empty() && stamp <= previous.back()) {
    throw InputError::at_line(
        file, line,
        fmt::format("timestamp {} does not increase (previous {:.6f}); timestamps must be "
                    "strictly increasing",
                    text, previous.back()));
  }
}

double parse_stamp(const std::string& text, const std::string& file, std::size_t line) {
  const double stamp = parse_double(text, file, line);
  if (!std::isfinite(stamp)) {
    throw InputError::at_line(file, line, fmt::format("timestamp '{}' is not finite", text));
  }
  return stamp;
}

StampedFileList read_stamped_file_list(const std::string& dir, const std::string& file) {
  StampedFileList list;
  for (const TextRow& row : read_text_table(file)) {
    if (row.fields.size() != 2) {
      throw InputError::at_line(
          file, row.line,
          fmt::format("expected 2 fields 'timestamp path', found {}", row.fields.size()));
    }
    const double stamp = parse_stamp(row.fields[0], file, row.line);
    require_increasing(file, row.line, stamp, row.fields[0], list.stamps);
    list.stamps.push_back(stamp);
    list.paths.push_back(resolve(dir, row.fields[1]));
  }
  if (list.stamps.empty()) throw InputError::at(file, "no frames listed (empty list)");
  return list;
}

std::string describe_type(const cv::Mat& image) {
  const int depth = image.depth();
  const char* bits = depth == CV_8U || depth == CV_8S     ? "8-bit"
                     : depth == CV_16U || depth == CV_16S ? "16-bit"
                     : depth == CV_32F || depth == CV_32S ? "32-bit"
                                                          : "64-bit";
  const char* kind = depth == CV_32F || depth == CV_64F ? " float" : "";
  return fmt::format("{}{} {}-channel", bits, kind, image.channels());
}

std::string describe_size(const cv::Mat& image) {
  return fmt::format("{}x{}", image.cols, image.rows);
}

/// Whether a JPEG file's bytes hold an end-of-image marker (FF D9) after the start; whatever
/// follows it (padding, a writer's trailer) is allowed, as decoders ignore it. libjpeg decodes a
/// cut-off file without an error (it only prints "Premature end of JPEG file" and fills the rest
/// grey), so OpenCV would hand back a picture. Entropy-coded data stuffs every FF with 00, so the
/// pair marks the end; a cut file whose EXIF thumbnail holds one still passes (a known gap).
bool jpeg_has_end_marker(const std::vector<unsigned char>& bytes) {
  for (std::size_t i = bytes.size() - 1; i >= 3; --i) {
    if (bytes[i - 1] == 0xFF && bytes[i] == 0xD9) return true;
  }
  return false;
}

/// An image file a list names: there, and a regular file (a folder, or a FIFO or device whose
/// read could block the run where Ctrl-C cannot stop it, is not). `context` ends the message
/// (" (listed by rgb.txt)" when the sequence is opened, empty when a frame is read).
void require_image_file(const std::string& path, const char* what, const std::string& context) {
  std::error_code ec;
  const fs::file_status status = fs::status(path, ec);
  if (!fs::exists(status)) {
    throw InputError::at(path, fmt::format("{} image not found{}", what, context));
  }
  if (!fs::is_regular_file(status)) {
    throw InputError::at(
        path, fmt::format("{} image is not a regular file ({}){}", what,
                          fs::is_directory(status) ? "a folder" : "a special file", context));
  }
}

cv::Mat read_image(const std::string& path, const char* what) {
  require_image_file(path, what, "");
  std::ifstream file(path, std::ios::binary | std::ios::ate);
  if (!file) {
    throw InputError::at(path, fmt::format("cannot open {} image: {}", what, std::strerror(errno)));
  }
  const std::streamoff size = file.tellg();
  if (size <= 0) throw InputError::at(path, fmt::format("{} image file is empty", what));
  std::vector<unsigned char> bytes(static_cast<std::size_t>(size));
  file.seekg(0);
  if (!file.read(reinterpret_cast<char*>(bytes.data()), size)) {
    throw InputError::at(path, fmt::format("cannot read {} image: {}", what, std::strerror(errno)));
  }
  const bool jpeg = bytes.size() >= 3 && bytes[0] == 0xFF && bytes[1] == 0xD8 && bytes[2] == 0xFF;
  if (jpeg && !jpeg_has_end_marker(bytes)) {
    throw InputError::at(
        path, fmt::format("{} image is a truncated JPEG (no end-of-image marker)", what));
  }
  cv::Mat image = cv::imdecode(bytes, cv::IMREAD_UNCHANGED);
  if (image.empty()) {
    throw InputError::at(
        path,
        fmt::format("cannot decode {} image (corrupt, truncated or unsupported format)", what));
  }
  return image;
}

cv::Mat to_bgr8(const cv::Mat& image, const std::string& path) {
  if (image.depth() != CV_8U) {
    throw InputError::at(path, fmt::format("RGB image must be 8-bit (3-channel colour or "
                                           "grayscale); found {}",
                                           describe_type(image)));
  }
  cv::Mat bgr;
  switch (image.channels()) {
    case 3:
      return image;
    case 1:
      cv::cvtColor(image, bgr, cv::COLOR_GRAY2BGR);
      return bgr;
    case 4:  // PNG with alpha: the colour is what matters.
      cv::cvtColor(image, bgr, cv::COLOR_BGRA2BGR);
      return bgr;
    default:
      throw InputError::at(path, fmt::format("RGB image must have 1, 3 or 4 channels; found {}",
                                             describe_type(image)));
  }
}

}  // namespace

void require_sequence_folder(const std::string& dir) {
  std::error_code ec;
  if (fs::is_directory(dir, ec)) return;
  throw InputError::at(dir, fs::exists(dir, ec) ? "is not a folder (a sequence is a folder)"
                                                : "sequence folder not found");
}

AssociationSource parse_association_source(const std::string& text, const std::string& key) {
  if (text == "auto") return AssociationSource::kAuto;
  if (text == "file") return AssociationSource::kFile;
  if (text == "timestamps") return AssociationSource::kTimestamps;
  throw ConfigError::for_key(key, fmt::format("'{}' is not one of auto, file, timestamps", text));
}

std::string to_string(AssociationSource source) {
  switch (source) {
    case AssociationSource::kAuto:
      return "auto";
    case AssociationSource::kFile:
      return "file";
    case AssociationSource::kTimestamps:
      return "timestamps";
  }
  return "?";
}

void SequenceOptions::validate() const {
  if (!std::isfinite(max_difference_s) || max_difference_s <= 0.0 || max_difference_s > 1.0) {
    throw ConfigError::for_key("dataset.max_difference",
                               fmt::format("must be in (0, 1] seconds (got {})", max_difference_s));
  }
  if (association == AssociationSource::kTimestamps && !associations_file.empty()) {
    throw ConfigError::for_key(
        "dataset.associations_file",
        fmt::format("'{}' is given but associations are computed from timestamps",
                    associations_file));
  }
}

namespace {

const camera::PinholeCamera& validated(const camera::PinholeCamera& camera) {
  camera.validate();
  return camera;
}

}  // namespace

std::string sequence_name(const std::string& dir) {
  fs::path p = fs::path(dir).lexically_normal();
  if (p.filename().empty()) p = p.parent_path();  // trailing separator
  std::string name = p.filename().string();
  if (name.empty() || name == "." || name == "..") {
    std::error_code ec;
    const fs::path absolute = fs::weakly_canonical(fs::absolute(dir), ec);
    if (!ec) name = absolute.filename().string();
  }
  return name;
}

TumDataset::TumDataset(const std::string& dir, const camera::PinholeCamera& camera,
                       const SequenceOptions& options)
    : dir_(dir),
      name_(sequence_name(dir)),
      input_camera_(validated(camera)),
      camera_(camera.undistorted()),
      undistorter_(camera) {
  options.validate();
  std::error_code ec;
  require_sequence_folder(dir_);

  const std::string default_associations = (fs::path(dir_) / "associations.txt").string();
  switch (options.association) {
    case AssociationSource::kAuto:
      if (!options.associations_file.empty()) {
        read_association_file(options.associations_file);
      } else if (fs::exists(default_associations, ec)) {
        read_association_file(default_associations);
      } else {
        associate_timestamps(options.max_difference_s);
      }
      break;
    case AssociationSource::kFile:
      read_association_file(options.associations_file.empty() ? default_associations
                                                              : options.associations_file);
      break;
    case AssociationSource::kTimestamps:
      associate_timestamps(options.max_difference_s);
      break;
  }

  if (options.check_files_on_open) {
    for (const FramePair& pair : pairs_) {
      const std::string listed_by = " (listed by " + association_description_ + ")";
      require_image_file(pair.rgb_path, "RGB", listed_by);
      require_image_file(pair.depth_path, "depth", listed_by);
    }
  }

  const std::string groundtruth = (fs::path(dir_) / "groundtruth.txt").string();
  if (fs::is_regular_file(groundtruth, ec)) {
    // Validated now, like the frame lists, so that a malformed line stops the run before its
    // first frame instead of after its last.
    if (options.check_groundtruth_on_open) read_tum_trajectory(groundtruth);
    groundtruth_path_ = groundtruth;
  }
  if (options.read_accelerometer) {
    const std::string accelerometer = (fs::path(dir_) / "accelerometer.txt").string();
    if (fs::is_regular_file(accelerometer, ec)) {
      accelerometer_ = AccelerometerLog::read(accelerometer);
    } else {
      spdlog::warn("{}: no accelerometer.txt, so the frames have no up direction", name_);
    }
  }

  spdlog::info(
      "{}: {} RGB-D frames ({}), camera '{}'{}{}{}", name_, pairs_.size(), association_description_,
      input_camera_.name, input_camera_.has_distortion() ? " (undistorting)" : "",
      groundtruth_path_ ? ", ground truth present" : ", no ground truth",
      accelerometer_ ? fmt::format(", {} accelerometer readings", accelerometer_->samples().size())
                     : "");
}

void TumDataset::read_association_file(const std::string& path) {
  constexpr double kFarPairS = 0.1;
  std::vector<double> rgb_stamps;
  std::unordered_map<std::string, std::size_t> depth_lines;  // depth image -> its line
  std::size_t far_pairs = 0;
  std::size_t first_far_line = 0;
  for (const TextRow& row : read_text_table(path)) {
    if (row.fields.size() != 4) {
      throw InputError::at_line(
          path, row.line,
          fmt::format("expected 4 fields 'rgb_timestamp rgb_path depth_timestamp depth_path', "
                      "found {}",
                      row.fields.size()));
    }
    FramePair pair;
    pair.rgb_timestamp_s = parse_stamp(row.fields[0], path, row.line);
    pair.rgb_path = resolve(dir_, row.fields[1]);
    pair.depth_timestamp_s = parse_stamp(row.fields[2], path, row.line);
    pair.depth_path = resolve(dir_, row.fields[3]);
    require_increasing(path, row.line, pair.rgb_timestamp_s, row.fields[0], rgb_stamps);
    // associate.py pairs each depth image once: one listed twice is an edited or broken file.
    const auto [earlier, first_use] = depth_lines.emplace(pair.depth_path, row.line);
    if (!first_use) {
      throw InputError::at_line(path, row.line,
                                fmt::format("depth image {} is paired already on line {}",
                                            row.fields[3], earlier->second));
    }
    const double gap_s = std::abs(pair.depth_timestamp_s - pair.rgb_timestamp_s);
    if (gap_s > kFarPairS && far_pairs++ == 0) first_far_line = row.line;
    rgb_stamps.push_back(pair.rgb_timestamp_s);
    pairs_.push_back(std::move(pair));
  }
  if (pairs_.empty()) throw InputError::at(path, "no frames listed (empty list)");
  if (far_pairs > 0) {
    // Not an error: a file made with associate.py --offset pairs stamps of clocks that differ.
    spdlog::warn(
        "{}: {} of {} pairs have depth more than {} s from their colour image (first: "
        "line {}); associate.py pairs within 0.02 s",
        path, far_pairs, pairs_.size(), kFarPairS, first_far_line);
  }
  association_description_ = fs::path(path).filename().string();
}

void TumDataset::associate_timestamps(double max_difference_s) {
  const std::string rgb_file = (fs::path(dir_) / "rgb.txt").string();
  const std::string depth_file = (fs::path(dir_) / "depth.txt").string();
  const StampedFileList rgb = read_stamped_file_list(dir_, rgb_file);
  const StampedFileList depth = read_stamped_file_list(dir_, depth_file);
  const std::vector<StampMatch> matches =
      associate(rgb.stamps, depth.stamps, 0.0, max_difference_s);
  if (matches.empty()) {
    throw InputError::at(
        dir_, fmt::format("no RGB/depth pairs: none of the {} stamps in rgb.txt is within {} s of "
                          "one of the {} stamps in depth.txt",
                          rgb.stamps.size(), max_difference_s, depth.stamps.size()));
  }
  pairs_.reserve(matches.size());
  for (const StampMatch& m : matches) {
    pairs_.push_back(
        {rgb.stamps[m.first], rgb.paths[m.first], depth.stamps[m.second], depth.paths[m.second]});
  }
  association_description_ = fmt::format(
      "associate(rgb.txt, depth.txt, max_difference {} s): {} of {} RGB and {} depth frames",
      max_difference_s, matches.size(), rgb.stamps.size(), depth.stamps.size());
}

double TumDataset::timestamp(std::size_t i) const {
  if (i >= pairs_.size()) {
    throw std::out_of_range(fmt::format("{}: frame {} of {}", name_, i, pairs_.size()));
  }
  return pairs_[i].rgb_timestamp_s;
}

RgbdFrame TumDataset::frame(std::size_t i) const {
  if (i >= pairs_.size()) {
    throw std::out_of_range(fmt::format("{}: frame {} of {}", name_, i, pairs_.size()));
  }
  const FramePair& pair = pairs_[i];
  const cv::Mat rgb = to_bgr8(read_image(pair.rgb_path, "RGB"), pair.rgb_path);
  const cv::Mat depth_raw = read_image(pair.depth_path, "depth");
  if (depth_raw.type() != CV_16UC1) {
    throw InputError::at(
        pair.depth_path,
        fmt::format("depth must be 16-bit single-channel (raw units, {} per metre); found {}",
                    input_camera_.depth_factor, describe_type(depth_raw)));
  }
  if (depth_raw.cols != input_camera_.width || depth_raw.rows != input_camera_.height) {
    throw InputError::at(
        pair.depth_path,
        fmt::format("depth image is {} but camera '{}' expects {}x{}", describe_size(depth_raw),
                    input_camera_.name, input_camera_.width, input_camera_.height));
  }
  if (rgb.size() != depth_raw.size()) {
    throw InputError::at(
        pair.rgb_path,
        fmt::format("RGB image is {} but its depth image {} is {} (camera '{}' expects {}x{}); "
                    "RGB and depth must be registered at the same size",
                    describe_size(rgb), pair.depth_path, describe_size(depth_raw),
                    input_camera_.name, input_camera_.width, input_camera_.height));
  }

  RgbdFrame frame;
  frame.index = i;
  frame.timestamp_s = pair.rgb_timestamp_s;
  frame.depth_timestamp_s = pair.depth_timestamp_s;
  frame.rgb_path = pair.rgb_path;
  frame.depth_path = pair.depth_path;
  frame.rgb = undistorter_.undistort_rgb(rgb);
  cv::Mat depth_m;
  depth_raw.convertTo(depth_m, CV_32F, 1.0 / input_camera_.depth_factor);  // 0 stays 0
  frame.depth_m = undistorter_.undistort_depth(depth_m);
  if (accelerometer_) frame.up_c = accelerometer_->up_in_camera_at(pair.rgb_timestamp_s);
  return frame;
}

}  // namespace ddl::io
