#pragma once
// PNG outputs: written whole or not at all (core/filesystem.h), and, for the pictures a run writes
// per frame (--save-masks, --save-inpainted), a log of the writes that failed, so that a full disk
// fails the run with a message instead of leaving a folder with holes behind an exit code 0.

#include <cstddef>
#include <filesystem>
#include <mutex>
#include <opencv2/core/mat.hpp>
#include <optional>
#include <string>
#include <string_view>

namespace ddl::io {

/// Encodes `image` as PNG and writes it whole or not at all. Throws OutputError naming `path` and
/// `what` it is when the image cannot be encoded (an empty image, a type PNG cannot hold) or the
/// file cannot be written. `compression_level` 0-9 (zlib's), or -1 for OpenCV's default (fast).
void write_png(const std::filesystem::path& path, const cv::Mat& image, std::string_view what,
               int compression_level = -1);

/// Writes the pictures of one kind a run produces frame by frame and keeps count of those that
/// could not be written. Safe to use from several threads.
class ImageOutputLog {
 public:
  /// `what` names the pictures in the messages ("the saved masks").
  explicit ImageOutputLog(std::string what);

  /// write_png; a failure is logged (the first one as an error, the rest counted) instead of
  /// thrown, so that the run goes on and writes its other outputs. Returns whether it was written.
  bool write_png(const std::filesystem::path& path, const cv::Mat& image);

  /// "N of M files of <what> could not be written; the first: <message>", or nothing when all
  /// were written.
  std::optional<std::string> error() const;

 private:
  std::string what_;
  mutable std::mutex mutex_;
  std::size_t attempted_ = 0;
  std::size_t failed_ = 0;
  std::string first_error_;
};

}  // namespace ddl::io
