#include "core/util/thread_pool.hpp"

#include <algorithm>
#include <map>
#include <memory>

namespace rotolidar {

ThreadPool::ThreadPool(int threads) {
  for (int w = 1; w < std::max(1, threads); ++w) workers_.emplace_back([this] { WorkerLoop(); });
}

ThreadPool::~ThreadPool() {
  {
    std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  start_cv_.notify_all();
  for (auto& t : workers_) t.join();
}

ThreadPool& ThreadPool::Shared(int threads) {
  static std::mutex registry_mutex;
  static std::map<int, std::unique_ptr<ThreadPool>> registry;
  std::lock_guard<std::mutex> lock(registry_mutex);
  std::unique_ptr<ThreadPool>& pool = registry[std::max(1, threads)];
  if (!pool) pool = std::make_unique<ThreadPool>(std::max(1, threads));
  return *pool;
}

// Indices are handed out one at a time under the lock: loops here have tens of items of ~0.1 ms each.
void ThreadPool::RunShare() {
  std::unique_lock<std::mutex> lock(mutex_);
  while (next_ < n_) {
    const int i = next_++;
    ++running_;
    lock.unlock();
    std::exception_ptr error;
    try {
      (*fn_)(i);
    } catch (...) {
      error = std::current_exception();
    }
    lock.lock();
    if (error && !error_) error_ = error;
    if (--running_ == 0 && next_ >= n_) done_cv_.notify_all();
  }
}

void ThreadPool::WorkerLoop() {
  long seen = 0;
  for (;;) {
    {
      std::unique_lock<std::mutex> lock(mutex_);
      start_cv_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
    }
    RunShare();
  }
}

void ThreadPool::ParallelFor(int n, const std::function<void(int)>& fn) {
  if (n <= 0) return;
  if (workers_.empty() || n == 1) {
    for (int i = 0; i < n; ++i) fn(i);
    return;
  }
  std::lock_guard<std::mutex> call(call_mutex_);
  {
    std::lock_guard<std::mutex> lock(mutex_);
    fn_ = &fn;
    n_ = n;
    next_ = 0;
    running_ = 0;
    error_ = nullptr;
    ++generation_;
  }
  start_cv_.notify_all();
  RunShare();
  std::exception_ptr error;
  {
    std::unique_lock<std::mutex> lock(mutex_);
    done_cv_.wait(lock, [&] { return next_ >= n_ && running_ == 0; });
    fn_ = nullptr;
    n_ = 0;
    error = error_;
  }
  if (error) std::rethrow_exception(error);
}

}  // namespace rotolidar
