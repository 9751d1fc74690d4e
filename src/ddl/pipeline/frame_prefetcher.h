#pragma once
// Loads frames of a dataset ahead of the pipeline in a thread of its own (decoding a JPEG and a
// PNG and undistorting them costs ~30 ms a frame on the reference machine), through a bounded
// queue. The order and content of frames is the dataset's, so results do not depend on it.
// Thread-safety: next() from one consumer thread.

#include <cstddef>
#include <exception>
#include <optional>
#include <thread>

#include "ddl/core/bounded_queue.h"
#include "ddl/io/dataset_reader.h"

namespace ddl::pipeline {

class FramePrefetcher {
 public:
  FramePrefetcher(const io::DatasetReader& dataset, std::size_t begin, std::size_t end,
                  std::size_t capacity = 4);
  ~FramePrefetcher();
  FramePrefetcher(const FramePrefetcher&) = delete;
  FramePrefetcher& operator=(const FramePrefetcher&) = delete;

  /// The next frame, std::nullopt at the end. Rethrows a loading error (ddl::InputError naming
  /// the file) at the frame where it happened.
  std::optional<io::RgbdFrame> next();

 private:
  struct Item {
    std::optional<io::RgbdFrame> frame;
    std::exception_ptr error;
  };
  BoundedQueue<Item> queue_;
  std::thread thread_;
};

}  // namespace ddl::pipeline
