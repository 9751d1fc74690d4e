#include "ddl/pipeline/segmentation_stage.h"

namespace ddl::pipeline {

SegmentationStage::SegmentationStage(FrameSource source, SegmentFn segment, std::size_t capacity,
                                     bool take_when_room)
    : queue_(capacity), take_when_room_(take_when_room) {
  thread_ = std::thread(
      [this, source = std::move(source), segment = std::move(segment)] { run(source, segment); });
}

SegmentationStage::~SegmentationStage() {
  queue_.close();
  if (thread_.joinable()) thread_.join();
}

void SegmentationStage::run(const FrameSource& source, const SegmentFn& segment) {
  while (true) {
    // Live input: the frame is taken only once tracking has room for it, so that it is the newest
    // one the camera has delivered when the CNN starts, not one that waits, segmented, while
    // tracking is busy with a slow frame.
    if (take_when_room_ && !queue_.wait_for_room()) break;
    Item item;
    try {
      std::optional<io::RgbdFrame> frame = source();
      if (!frame) break;
      CnnMask cnn = segment(*frame);
      item.segmented = SegmentedFrame{std::move(*frame), std::move(cnn)};
    } catch (...) {
      item.error = std::current_exception();
    }
    const bool failed = item.error != nullptr;
    if (!queue_.push(std::move(item)) || failed) break;
  }
  queue_.close();
}

std::optional<SegmentedFrame> SegmentationStage::next() {
  std::optional<Item> item = queue_.pop();
  if (!item) return std::nullopt;
  if (item->error) std::rethrow_exception(item->error);
  return std::move(item->segmented);
}

}  // namespace ddl::pipeline
