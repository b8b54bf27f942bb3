#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include "core/util/thread_pool.hpp"

namespace rotolidar {
namespace {

TEST(ThreadPool, RunsEveryIndexOnceOverManyLoops) {
  ThreadPool pool(4);
  for (int loop = 0; loop < 200; ++loop) {
    const int n = 1 + loop % 37;
    std::vector<std::atomic<int>> hits(n);
    pool.ParallelFor(n, [&](int i) { ++hits[i]; });
    for (int i = 0; i < n; ++i) ASSERT_EQ(hits[i].load(), 1) << "loop " << loop << " index " << i;
  }
}

TEST(ThreadPool, UsesMoreThanOneThreadAndReusesThem) {
  ThreadPool& pool = ThreadPool::Shared(3);
  EXPECT_EQ(&pool, &ThreadPool::Shared(3));  // one pool per size, reused
  std::mutex m;
  std::set<std::thread::id> ids;
  for (int loop = 0; loop < 20; ++loop)
    pool.ParallelFor(12, [&](int) {
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
      std::lock_guard<std::mutex> lock(m);
      ids.insert(std::this_thread::get_id());
    });
  EXPECT_GE(ids.size(), 2u);
  EXPECT_LE(ids.size(), 3u);  // the caller plus two workers, the same ones every loop
}

TEST(ThreadPool, RethrowsTheFirstErrorAfterAllCallsFinished) {
  ThreadPool pool(3);
  std::atomic<int> done{0};
  EXPECT_THROW(pool.ParallelFor(50,
                                [&](int i) {
                                  ++done;
                                  if (i == 7) throw std::runtime_error("boom");
                                }),
               std::runtime_error);
  EXPECT_EQ(done.load(), 50);  // the others still ran
  std::atomic<int> after{0};
  pool.ParallelFor(10, [&](int) { ++after; });  // the pool still works
  EXPECT_EQ(after.load(), 10);
}

}  // namespace
}  // namespace rotolidar
