#include "ddl/pipeline/segmentation_stage.h"

namespace ddl::pipeline {

SegmentationStage::SegmentationStage(FrameSource source, SegmentFn segment, std::size_t capacity)
    : queue_(capacity) {
  thread_ = std::thread(
      [this, source = std::move(source), segment = std::move(segment)] { run(source, segment); });
}

SegmentationStage::~SegmentationStage() {
  queue_.close();
  if (thread_.joinable()) thread_.join();
}

void SegmentationStage::run(const FrameSource& source, const SegmentFn& segment) {
  while (true) {
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
