#pragma once

// Small threading helpers of the evaluation pipelines: a bounded queue between a reader thread and
// the processing thread, and a loop that runs a producer on its own thread.

#include <algorithm>
#include <chrono>
#include <condition_variable>
#include <cstddef>
#include <deque>
#include <exception>
#include <mutex>
#include <optional>
#include <thread>
#include <utility>

#include "imumatch/core/time.h"  // SteadyClock, MsSince

namespace imumatch {

// A bounded FIFO between the reader thread and the processing thread.
template <typename T>
class BoundedQueue {
 public:
  explicit BoundedQueue(size_t capacity) : capacity_(std::max<size_t>(1, capacity)) {}
  // Returns false when the queue was closed (the consumer gave up).
  bool Push(T item) {
    std::unique_lock<std::mutex> lock(mutex_);
    not_full_.wait(lock, [&] { return closed_ || items_.size() < capacity_; });
    if (closed_) return false;
    items_.push_back(std::move(item));
    not_empty_.notify_one();
    return true;
  }
  T Pop() {
    std::unique_lock<std::mutex> lock(mutex_);
    not_empty_.wait(lock, [&] { return !items_.empty(); });
    T item = std::move(items_.front());
    items_.pop_front();
    not_full_.notify_one();
    return item;
  }
  void Close() {
    std::lock_guard<std::mutex> lock(mutex_);
    closed_ = true;
    not_full_.notify_all();
  }

 private:
  size_t capacity_;
  std::mutex mutex_;
  std::condition_variable not_full_, not_empty_;
  std::deque<T> items_;
  bool closed_ = false;
};

// Runs producer(i) for i in [0, n) on its own thread (or inline when capacity is 0) and hands the
// items to the consumer in order. The reader stops early when the consumer throws; a producer's
// exception is rethrown in the calling thread.
template <typename T, typename Producer, typename Consumer>
void RunPipelined(size_t n, int capacity, Producer producer, Consumer consumer) {
  if (capacity <= 0) {
    for (size_t i = 0; i < n; ++i) consumer(producer(i));
    return;
  }
  // An exception thrown by the producer (an unreadable file) must not end the process from the
  // reader thread: it travels through the queue as an empty item and is rethrown here, in the
  // consumer's thread, where the caller can catch it.
  BoundedQueue<std::optional<T>> queue(static_cast<size_t>(capacity));
  std::exception_ptr error;
  std::thread reader([&] {
    for (size_t i = 0; i < n; ++i) {
      std::optional<T> item;
      try {
        item.emplace(producer(i));
      } catch (...) {
        error = std::current_exception();
        queue.Push(std::nullopt);
        return;
      }
      if (!queue.Push(std::move(item))) return;
    }
  });
  struct Joiner {
    BoundedQueue<std::optional<T>>& q;
    std::thread& t;
    ~Joiner() {
      q.Close();
      t.join();
    }
  } joiner{queue, reader};
  for (size_t i = 0; i < n; ++i) {
    std::optional<T> item = queue.Pop();
    if (!item) std::rethrow_exception(error);  // written before the push that woke us
    consumer(std::move(*item));
  }
}

}  // namespace imumatch
