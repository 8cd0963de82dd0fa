#pragma once

#include <exception>
#include <vector>

#include <opencv2/core/utility.hpp>

namespace imumatch {

// Runs task(i) for i in [0, count) on OpenCV's thread pool, each as its own stripe (one after the
// other when the pool has a single thread; cv::setNumThreads sets its size). Which thread runs
// which task is the backend's choice: Debian's OpenCV runs on TBB, which splits the range in
// halves, so with two threads tasks [0, count/2) run on the calling thread and the rest on the
// other (measured with count 4 and tasks of 30/28/15/23 ms: {0, 1} and {2, 3}, every time), not
// "in index order as threads free up". Give each call as many tasks as there are cores, of
// about equal length. An exception thrown by a task does not escape the pool: the first one, in
// task order, is rethrown here once all tasks have ended.
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
