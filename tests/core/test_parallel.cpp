// parallel_for on the process-wide thread pool: every item exactly once, whatever the thread
// count; the first exception reaches the caller and the pool stays usable; loops inside loops
// and loops started by several threads at once run (serially) instead of deadlocking; pool
// threads have an alternate signal stack, so a stack overflow still reaches a handler.
#include "core/parallel.hpp"

#include <gtest/gtest.h>

#include <atomic>
#include <csignal>
#include <mutex>
#include <set>
#include <stdexcept>
#include <thread>
#include <vector>

#include <sys/wait.h>
#include <unistd.h>

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

// A stack overflow in a pool thread must still reach a SIGSEGV handler that runs on an
// alternate stack (SA_ONSTACK), as the CLI's cleanup of partial output does (io/output.cpp).
// sigaltstack() is per thread: every pool thread sets up its own...
TEST(ParallelFor, PoolThreadsHaveAnAlternateSignalStack) {
  const auto main_id = std::this_thread::get_id();
  std::atomic<int> waiting{0}, checked{0};
  std::atomic<bool> all_enabled{true};
  // Two items that each wait for the other to start: a pool thread runs one of them.
  parallel_for(2, 2, [&](std::size_t) {
    if (std::this_thread::get_id() != main_id) {
      stack_t ss{};
      const bool ok = ::sigaltstack(nullptr, &ss) == 0 && !(ss.ss_flags & SS_DISABLE) && ss.ss_size >= 32768;
      if (!ok) all_enabled = false;
      ++checked;
    }
    ++waiting;
    while (waiting.load() < 2) std::this_thread::yield();
  });
  EXPECT_EQ(checked.load(), 1);
  EXPECT_TRUE(all_enabled.load());
}

// ... and with one, a thread that overflows its stack reaches the handler. Run in a forked
// child whose thread recurses without end; the handler ends the child with status 42.
int recurse(int depth) {
  volatile char frame[1024];
  frame[0] = static_cast<char>(depth);
  return depth < 0 ? 0 : recurse(depth + 1) + frame[0];  // depth never goes negative
}

extern "C" void exit_42(int) { ::_exit(42); }

TEST(ParallelFor, AStackOverflowReachesTheHandlerOnTheAlternateStack) {
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) {
    struct sigaction act {};
    act.sa_handler = exit_42;
    act.sa_flags = SA_ONSTACK;
    sigemptyset(&act.sa_mask);
    ::sigaction(SIGSEGV, &act, nullptr);
    ::sigaction(SIGBUS, &act, nullptr);
    std::thread t([] {
      const detail::AlternateSignalStack signal_stack;
      (void)recurse(0);
    });
    t.join();
    ::_exit(3);
  }
  int status = 0;
  ASSERT_EQ(::waitpid(child, &status, 0), child);
  ASSERT_TRUE(WIFEXITED(status)) << "the child was ended by signal " << (WIFSIGNALED(status) ? WTERMSIG(status) : 0);
  EXPECT_EQ(WEXITSTATUS(status), 42);
}

}  // namespace
}  // namespace vproxq
