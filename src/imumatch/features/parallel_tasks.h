#pragma once

#include <exception>
#include <vector>

#include <opencv2/core/utility.hpp>

namespace imumatch {

// Runs task(i) for i in [0, count) on OpenCV's thread pool, each as its own stripe taken in index
// order by the pool's threads as they free up (one after the other when the pool has a single
// thread; cv::setNumThreads sets its size). An exception thrown by a task does not escape the
// pool: the first one, in task order, is rethrown here once all tasks have ended.
template <typename Task>
void RunTasks(int count, Task&& task) {
  std::vector<std::exception_ptr> errors(static_cast<size_t>(count));
  cv::parallel_for_(
      cv::Range(0, count),
      [&](const cv::Range& range) {
        for (int i = range.start; i < range.end; ++i) {
          try {
            task(i);
          } catch (...) {
            errors[static_cast<size_t>(i)] = std::current_exception();
          }
        }
      },
      count);
  for (const std::exception_ptr& e : errors) {
    if (e) std::rethrow_exception(e);
  }
}

}  // namespace imumatch
