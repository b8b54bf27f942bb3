#pragma once
// A fixed pool of worker threads for the estimator's data-parallel loops (feature sectors and rings): threads are
// started once and reused by every scan, instead of being spawned per call.
//
// Contract: ParallelFor(n, fn) runs fn(0) .. fn(n-1), each exactly once, on the pool's workers plus the calling
// thread, and returns when all have finished. Each call must write only its own outputs (results then never
// depend on the number of workers). The first exception thrown by any fn is rethrown in the caller after all
// calls finished. One ParallelFor at a time per pool (concurrent callers are serialised by a mutex).
// Ownership: the pool owns its threads and joins them in its destructor. Shared(n) hands out one process-wide
// pool per worker count, created on first use and alive until exit.
#include <condition_variable>
#include <exception>
#include <functional>
#include <mutex>
#include <thread>
#include <vector>

namespace rotolidar {

class ThreadPool {
 public:
  /// A pool running loops on `threads` threads in total (the caller counts as one): threads - 1 workers.
  explicit ThreadPool(int threads);
  ~ThreadPool();
  ThreadPool(const ThreadPool&) = delete;
  ThreadPool& operator=(const ThreadPool&) = delete;

  void ParallelFor(int n, const std::function<void(int)>& fn);
  int threads() const { return int(workers_.size()) + 1; }

  /// The process-wide pool with `threads` threads in total (threads >= 1).
  static ThreadPool& Shared(int threads);

 private:
  void WorkerLoop();
  void RunShare();  ///< takes indices of the current loop until none is left

  std::vector<std::thread> workers_;
  std::mutex call_mutex_;  ///< one loop at a time
  std::mutex mutex_;
  std::condition_variable start_cv_, done_cv_;
  const std::function<void(int)>* fn_ = nullptr;
  int n_ = 0;
  int next_ = 0;       ///< next index to hand out (under mutex_)
  int running_ = 0;    ///< calls in flight
  long generation_ = 0;
  bool stop_ = false;
  std::exception_ptr error_;
};

}  // namespace rotolidar
