#pragma once
// Semantic segmentation ahead of tracking (DDL-SLAM section III-B in a thread of its own): a
// worker reads frames from a source (the FramePrefetcher), computes each frame's CNN mask and
// hands frame and mask on through a bounded queue, in frame order. The CNN output depends only on
// the frame, so tracking gets the same masks as with inline segmentation in either run mode
// (deterministic runs stay reproducible); it only stops waiting for them while the CNN works on
// the next frames.
//
// Shutdown (ARCHITECTURE.md section 3): the end of the source closes the queue and next() returns
// std::nullopt after the last frame; an error of the source or of the CNN is handed on as the
// item of the frame where it happened (next() rethrows it) and ends the worker; the destructor
// (early stop, Ctrl-C, an error downstream) closes the queue, which ends the worker at its next
// push, and joins it. The source must outlive the stage.
// Thread-safety: next() from one consumer thread; `source` and `segment` are called from the
// worker thread only.

#include <cstddef>
#include <exception>
#include <functional>
#include <optional>
#include <thread>

#include "ddl/core/bounded_queue.h"
#include "ddl/io/rgbd_frame.h"
#include "ddl/pipeline/dynamic_front_end.h"

namespace ddl::pipeline {

/// A frame and its CNN mask, computed ahead of tracking.
struct SegmentedFrame {
  io::RgbdFrame frame;
  CnnMask cnn;
};

class SegmentationStage {
 public:
  /// The next frame, std::nullopt at the end (io::DatasetReader order).
  using FrameSource = std::function<std::optional<io::RgbdFrame>()>;
  /// The CNN mask of one frame (System::segment).
  using SegmentFn = std::function<CnnMask(const io::RgbdFrame&)>;

  /// Starts the worker. `capacity`: frames segmented ahead of the consumer (at least 1).
  /// `take_when_room` (live input): the worker takes a frame from the source only when the queue
  /// has room for it, so that a frame never waits, segmented, for the consumer.
  SegmentationStage(FrameSource source, SegmentFn segment, std::size_t capacity = 2,
                    bool take_when_room = false);
  ~SegmentationStage();
  SegmentationStage(const SegmentationStage&) = delete;
  SegmentationStage& operator=(const SegmentationStage&) = delete;

  /// The next frame with its mask, std::nullopt at the end. Rethrows an error of the source or
  /// of the CNN at the frame where it happened.
  std::optional<SegmentedFrame> next();

 private:
  struct Item {
    std::optional<SegmentedFrame> segmented;
    std::exception_ptr error;
  };
  void run(const FrameSource& source, const SegmentFn& segment);

  BoundedQueue<Item> queue_;
  bool take_when_room_;
  std::thread thread_;
};

}  // namespace ddl::pipeline
