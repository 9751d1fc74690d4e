#include "ddl/pipeline/frame_prefetcher.h"

namespace ddl::pipeline {

FramePrefetcher::FramePrefetcher(const io::DatasetReader& dataset, std::size_t begin,
                                 std::size_t end, std::size_t capacity)
    : queue_(capacity) {
  thread_ = std::thread([this, &dataset, begin, end] {
    for (std::size_t i = begin; i < end; ++i) {
      Item item;
      try {
        item.frame = dataset.frame(i);
      } catch (...) {
        item.error = std::current_exception();
      }
      const bool failed = item.error != nullptr;
      if (!queue_.push(std::move(item)) || failed) break;
    }
    queue_.close();
  });
}

FramePrefetcher::~FramePrefetcher() {
  queue_.close();
  if (thread_.joinable()) thread_.join();
}

std::optional<io::RgbdFrame> FramePrefetcher::next() {
  std::optional<Item> item = queue_.pop();
  if (!item) return std::nullopt;
  if (item->error) std::rethrow_exception(item->error);
  return std::move(item->frame);
}

}  // namespace ddl::pipeline
