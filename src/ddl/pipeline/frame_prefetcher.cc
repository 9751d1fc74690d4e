#include "ddl/pipeline/frame_prefetcher.h"

#include "ddl/core/error.h"

namespace ddl::pipeline {

FramePrefetcher::FramePrefetcher(const io::DatasetReader& dataset, std::size_t begin,
                                 std::size_t end, const PrefetchOptions& options)
    : options_(options), queue_(options.drop_late ? 1 : options.capacity) {
  if (options_.drop_late && options_.pacer == nullptr) {
    throw ConfigError::for_key("--drop-late-frames", "needs --playback-rate (a paced run)");
  }
  thread_ = std::thread([this, &dataset, begin, end] { load(dataset, begin, end); });
}

void FramePrefetcher::load(const io::DatasetReader& dataset, std::size_t begin, std::size_t end) {
  FramePacer* const pacer = options_.pacer;
  for (std::size_t i = begin; i < end; ++i) {
    Item item;
    try {
      if (pacer != nullptr) {
        const double stamp_s = dataset.timestamp(i);
        // The camera has delivered the next frame already: this one is gone unread.
        if (options_.drop_late && i + 1 < end && pacer->is_due(dataset.timestamp(i + 1))) {
          ++dropped_;
          continue;
        }
        if (!pacer->wait_for(stamp_s)) break;  // shutting down or stopped: no more frames
      }
      item.frame = dataset.frame(i);
    } catch (...) {
      item.error = std::current_exception();
    }
    const bool failed = item.error != nullptr;
    if (options_.drop_late && !failed) {
      const std::optional<std::size_t> displaced = queue_.push_displacing_oldest(std::move(item));
      if (!displaced) break;
      dropped_ += *displaced;
    } else if (!queue_.push(std::move(item)) || failed) {
      break;
    }
  }
  queue_.close();
}

FramePrefetcher::~FramePrefetcher() {
  if (options_.pacer != nullptr) options_.pacer->cancel();
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
