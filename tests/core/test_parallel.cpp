// parallel_for on the process-wide thread pool: every item exactly once, whatever the thread
// count; the first exception reaches the caller and the pool stays usable; loops inside loops
// and loops started by several threads at once run (serially) instead of deadlocking.
#include "core/parallel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

namespace vproxq {
namespace {

TEST(ParallelFor, EveryItemExactlyOnceOverManyCalls) {
  for (int threads : {1, 2, 3, 8}) {
    for (std::size_t n : {0u, 1u, 2u, 7u, 1000u}) {
      for (int repeat = 0; repeat < 50; ++repeat) {
        std::vector<std::atomic<int>> hits(n);
        parallel_for(n, threads, [&](std::size_t i) { ++hits[i]; });
        for (std::size_t i = 0; i < n; ++i) ASSERT_EQ(hits[i].load(), 1) << threads << " " << n << " " << i;
      }
    }
  }
}

TEST(ParallelFor, UsesSeveralThreads) {
  std::mutex m;
  std::set<std::thread::id> ids;
  std::atomic<int> waiting{0};
  // Two items that each wait for the other to start: only two threads can finish them.
  parallel_for(2, 2, [&](std::size_t) {
    {
      std::lock_guard<std::mutex> lock(m);
      ids.insert(std::this_thread::get_id());
    }
    ++waiting;
    while (waiting.load() < 2) std::this_thread::yield();
  });
  EXPECT_EQ(ids.size(), 2u);
}

TEST(ParallelFor, FirstExceptionReachesTheCallerAndThePoolStaysUsable) {
  for (int round = 0; round < 20; ++round) {
    std::atomic<int> ran{0};
    EXPECT_THROW(parallel_for(100, 3,
                              [&](std::size_t i) {
                                ++ran;
                                if (i == 17) throw std::runtime_error("item 17");
                              }),
                 std::runtime_error);
    EXPECT_LE(ran.load(), 100);
    std::atomic<int> sum{0};
    parallel_for(100, 3, [&](std::size_t i) { sum += static_cast<int>(i); });
    EXPECT_EQ(sum.load(), 4950);
  }
}

TEST(ParallelFor, NestedAndConcurrentLoopsComplete) {
  std::atomic<int> inner{0};
  parallel_for(8, 2, [&](std::size_t) { parallel_for(10, 2, [&](std::size_t) { ++inner; }); });
  EXPECT_EQ(inner.load(), 80);
  std::atomic<long> total{0};
  std::vector<std::thread> callers;
  for (int c = 0; c < 4; ++c)
    callers.emplace_back([&] {
      for (int k = 0; k < 100; ++k) parallel_for(50, 2, [&](std::size_t i) { total += static_cast<long>(i); });
    });
  for (auto& t : callers) t.join();
  EXPECT_EQ(total.load(), 4L * 100 * 1225);
}

}  // namespace
}  // namespace vproxq
