#pragma once
// A bounded blocking multi-producer multi-consumer queue that can be closed. Closing is how
// shutdown propagates between pipeline stages (ARCHITECTURE.md section 3): after close(), push()
// refuses new items and pop() drains what is left, then returns std::nullopt.
// Thread-safe: every method may be called from any thread.

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <mutex>
#include <optional>

namespace ddl {

template <typename T>
class BoundedQueue {
 public:
  explicit BoundedQueue(std::size_t capacity) : capacity_(capacity == 0 ? 1 : capacity) {}

  BoundedQueue(const BoundedQueue&) = delete;
  BoundedQueue& operator=(const BoundedQueue&) = delete;

  /// Blocks while full. Returns false (and drops the item) when the queue is closed.
  bool push(T item) {
    std::unique_lock lock(mutex_);
    not_full_.wait(lock, [&] { return closed_ || items_.size() < capacity_; });
    if (closed_) return false;
    items_.push_back(std::move(item));
    not_empty_.notify_one();
    return true;
  }

  /// Blocks while full and open: true once there is room for an item, false when closed. A
  /// producer that should hand on the newest input (a live camera's frame) waits here before it
  /// takes its input, instead of holding an item that ages while push() blocks.
  bool wait_for_room() {
    std::unique_lock lock(mutex_);
    not_full_.wait(lock, [&] { return closed_ || items_.size() < capacity_; });
    return !closed_;
  }

  /// Never blocks: when full, the oldest items make room (a camera's frame buffer keeps the
  /// newest frames). Returns how many were displaced, std::nullopt (item dropped) when closed.
  std::optional<std::size_t> push_displacing_oldest(T item) {
    std::lock_guard lock(mutex_);
    if (closed_) return std::nullopt;
    std::size_t displaced = 0;
    for (; items_.size() >= capacity_; ++displaced) items_.pop_front();
    items_.push_back(std::move(item));
    not_empty_.notify_one();
    return displaced;
  }

  /// Never blocks. Returns false when full or closed.
  bool try_push(T item) {
    std::lock_guard lock(mutex_);
    if (closed_ || items_.size() >= capacity_) return false;
    items_.push_back(std::move(item));
    not_empty_.notify_one();
    return true;
  }

  /// Blocks while empty and open. Returns std::nullopt once closed and drained.
  std::optional<T> pop() {
    std::unique_lock lock(mutex_);
    not_empty_.wait(lock, [&] { return closed_ || !items_.empty(); });
    if (items_.empty()) return std::nullopt;
    T item = std::move(items_.front());
    items_.pop_front();
    not_full_.notify_one();
    return item;
  }

  /// Never blocks. Returns std::nullopt when nothing is queued.
  std::optional<T> try_pop() {
    std::lock_guard lock(mutex_);
    if (items_.empty()) return std::nullopt;
    T item = std::move(items_.front());
    items_.pop_front();
    not_full_.notify_one();
    return item;
  }

  void close() {
    std::lock_guard lock(mutex_);
    closed_ = true;
    not_empty_.notify_all();
    not_full_.notify_all();
  }

  bool closed() const {
    std::lock_guard lock(mutex_);
    return closed_;
  }

  std::size_t size() const {
    std::lock_guard lock(mutex_);
    return items_.size();
  }

  std::size_t capacity() const { return capacity_; }

 private:
  const std::size_t capacity_;
  mutable std::mutex mutex_;
  std::condition_variable not_empty_;
  std::condition_variable not_full_;
  std::deque<T> items_;
  bool closed_ = false;
};

}  // namespace ddl
