#pragma once
// Loads frames of a dataset ahead of the pipeline in a thread of its own (decoding a JPEG and a
// PNG and undistorting them costs ~30 ms a frame on the reference machine), through a bounded
// queue. The order and content of frames is the dataset's, so results do not depend on it.
//
// Paced (a FramePacer): a frame is loaded when it is due, as a live camera delivers it. Live
// (`drop_late`, paced only): like a camera with a one-frame buffer, a frame whose successor is
// due already is skipped without being loaded, and a loaded frame the pipeline has not taken yet
// when the next one arrives is replaced by it; frames_dropped() counts both. Which frames are
// dropped then depends on timing, so a live run is not reproducible.
// Thread-safety: next() from one consumer thread; frames_dropped() from any.

#include <atomic>
#include <cstddef>
#include <exception>
#include <optional>
#include <thread>

#include "ddl/core/bounded_queue.h"
#include "ddl/io/dataset_reader.h"
#include "ddl/pipeline/frame_pacer.h"

namespace ddl::pipeline {

struct PrefetchOptions {
  std::size_t capacity = 4;     // frames loaded ahead (1 when frames are dropped)
  FramePacer* pacer = nullptr;  // paces the loading when set; cancelled by the destructor
  bool drop_late = false;       // needs a pacer
};

class FramePrefetcher {
 public:
  /// ConfigError (naming --drop-late-frames) when drop_late is set without a pacer.
  FramePrefetcher(const io::DatasetReader& dataset, std::size_t begin, std::size_t end,
                  const PrefetchOptions& options = {});
  ~FramePrefetcher();
  FramePrefetcher(const FramePrefetcher&) = delete;
  FramePrefetcher& operator=(const FramePrefetcher&) = delete;

  /// The next frame, std::nullopt at the end. Rethrows a loading error (ddl::InputError naming
  /// the file) at the frame where it happened.
  std::optional<io::RgbdFrame> next();

  /// Frames skipped or replaced so far (live mode).
  std::size_t frames_dropped() const { return dropped_.load(); }

 private:
  struct Item {
    std::optional<io::RgbdFrame> frame;
    std::exception_ptr error;
  };
  void load(const io::DatasetReader& dataset, std::size_t begin, std::size_t end);

  PrefetchOptions options_;
  BoundedQueue<Item> queue_;
  std::atomic<std::size_t> dropped_{0};
  std::thread thread_;
};

}  // namespace ddl::pipeline
