#include "ddl/io/image_output.h"

#include <fmt/format.h>
#include <spdlog/spdlog.h>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <utility>
#include <vector>

#include "ddl/core/error.h"
#include "ddl/core/filesystem.h"

namespace ddl::io {

void write_png(const std::filesystem::path& path, const cv::Mat& image, std::string_view what,
               int compression_level) {
  std::vector<unsigned char> bytes;
  std::vector<int> params;
  if (compression_level >= 0) params = {cv::IMWRITE_PNG_COMPRESSION, compression_level};
  bool encoded = false;
  try {
    encoded = !image.empty() && cv::imencode(".png", image, bytes, params);
  } catch (const cv::Exception& e) {
    throw OutputError::at(path.string(), fmt::format("cannot encode {}: {}", what, e.what()));
  }
  if (!encoded) throw OutputError::at(path.string(), fmt::format("cannot encode {}", what));
  write_file_atomically(
      path, what, std::string_view(reinterpret_cast<const char*>(bytes.data()), bytes.size()));
}

ImageOutputLog::ImageOutputLog(std::string what) : what_(std::move(what)) {}

bool ImageOutputLog::write_png(const std::filesystem::path& path, const cv::Mat& image) {
  std::string message;
  try {
    io::write_png(path, image, what_);
  } catch (const Error& e) {
    message = e.what();
  }
  std::lock_guard lock(mutex_);
  ++attempted_;
  if (message.empty()) return true;
  if (failed_++ == 0) {
    spdlog::error("{} (further failures of {} are counted, not shown)", message, what_);
    first_error_ = std::move(message);
  }
  return false;
}

std::optional<std::string> ImageOutputLog::error() const {
  std::lock_guard lock(mutex_);
  if (failed_ == 0) return std::nullopt;
  return fmt::format("{} of {} files of {} could not be written; the first: {}", failed_,
                     attempted_, what_, first_error_);
}

}  // namespace ddl::io
