#pragma once
// A bounded FIFO between two threads with its storage allocated once: push waits while it
// is full, pop while it is empty, and close() ends both waits (pop then drains what is left).
#include <array>
#include <condition_variable>
#include <cstddef>
#include <mutex>
#include <optional>

namespace rgbdo {

template <typename T, std::size_t N>
class BoundedQueue {
 public:
  // False when the queue was closed (the item is not queued).
  bool push(T item) {
    std::unique_lock<std::mutex> lock(mutex_);
    not_full_.wait(lock, [&] { return size_ < N || closed_; });
    if (closed_) return false;
    items_[(head_ + size_) % N] = std::move(item);
    ++size_;
    not_empty_.notify_one();
    return true;
  }
  // Empty when closed and drained.
  std::optional<T> pop() {
    std::unique_lock<std::mutex> lock(mutex_);
    not_empty_.wait(lock, [&] { return size_ > 0 || closed_; });
    return take_locked();
  }
  // As pop(), but gives up (empty) after `timeout` even when not closed.
  template <typename Duration>
  std::optional<T> pop_for(Duration timeout) {
    std::unique_lock<std::mutex> lock(mutex_);
    not_empty_.wait_for(lock, timeout, [&] { return size_ > 0 || closed_; });
    return take_locked();
  }
  void close() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    not_full_.notify_all();
    not_empty_.notify_all();
  }
  bool closed_and_empty() const {
    std::lock_guard<std::mutex> lock(mutex_);
    return closed_ && size_ == 0;
  }

 private:
  std::optional<T> take_locked() {
    if (size_ == 0) return std::nullopt;
    std::optional<T> item(std::move(items_[head_]));
    head_ = (head_ + 1) % N;
    --size_;
    not_full_.notify_one();
    return item;
  }
  mutable std::mutex mutex_;
  std::condition_variable not_full_, not_empty_;
  std::array<T, N> items_{};
  std::size_t head_ = 0, size_ = 0;
  bool closed_ = false;
};

}  // namespace rgbdo
