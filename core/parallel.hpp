#pragma once
// A minimal parallel loop: items are claimed dynamically, so results must not depend on
// which thread runs which item (write results by index).
//
// The threads are a process-wide pool, started on first use and kept: starting and joining
// threads on every call cost milliseconds per frame on small scenes (1,000 frames of two
// 96-triangle spheres ran 4x slower on 2 threads than on 1). A call waits only for the pool
// threads that joined its loop; one that wakes after the caller has run out of items stays
// out. A parallel_for inside another one (or while another thread's runs) runs serially in
// its caller.
#include <algorithm>
#include <atomic>
#include <condition_variable>
#include <cstddef>
#include <cstdint>
#include <exception>
#include <memory>
#include <mutex>
#include <thread>
#include <type_traits>
#include <vector>

#include <signal.h>

namespace vproxq {

/// Number of worker threads to use for `requested` (0 = all hardware threads).
inline int resolve_threads(int requested) {
  if (requested > 0) return requested;
  const unsigned hw = std::thread::hardware_concurrency();
  return hw == 0 ? 1 : static_cast<int>(hw);
}

namespace detail {

/// An alternate signal stack for the calling thread while this lives. A handler installed
/// with SA_ONSTACK then runs even for a stack overflow of this thread, which leaves no room on
/// the thread's own stack: the CLI's fatal-signal handler removes the run's partial output
/// (io/output.cpp), and the main thread gets its own stack there. sigaltstack() is per thread,
/// so each pool thread sets one up. Without one (the call fails), such a handler cannot run
/// on an overflow: the next run into the directory removes the temporaries then.
class AlternateSignalStack {
 public:
  AlternateSignalStack() : memory_(new char[kSize]) {
    stack_t ss{};
    ss.ss_sp = memory_.get();
    ss.ss_size = kSize;
    installed_ = ::sigaltstack(&ss, nullptr) == 0;
  }
  ~AlternateSignalStack() {
    if (!installed_) return;
    stack_t ss{};
    ss.ss_flags = SS_DISABLE;
    ::sigaltstack(&ss, nullptr);
  }
  AlternateSignalStack(const AlternateSignalStack&) = delete;
  AlternateSignalStack& operator=(const AlternateSignalStack&) = delete;

 private:
  static constexpr std::size_t kSize = std::size_t{1} << 16;
  std::unique_ptr<char[]> memory_;
  bool installed_ = false;
};

class ThreadPool {
 public:
  using Call = void (*)(void*, std::size_t);

  static ThreadPool& instance() {
    static ThreadPool pool;
    return pool;
  }

  /// Whether the calling thread is inside a parallel loop's body.
  static bool& in_loop() {
    thread_local bool inside = false;
    return inside;
  }

  /// Runs call(ctx, i) for i in [0, n) on the caller and up to `helpers` pool threads.
  /// Returns false, running nothing, when another loop holds the pool.
  bool run(std::size_t n, std::size_t helpers, void* ctx, Call call) {
    std::unique_lock<std::mutex> claim(run_mutex_, std::try_to_lock);
    if (!claim.owns_lock()) return false;
    {
      std::lock_guard<std::mutex> lock(mutex_);
      while (threads_.size() < helpers) {
        const std::size_t index = threads_.size();
        threads_.emplace_back([this, index] { worker(index); });
      }
      n_ = n;
      ctx_ = ctx;
      call_ = call;
      next_ = 0;
      helpers_ = helpers;
      error_ = nullptr;
      open_ = true;
      ++generation_;
    }
    wake_.notify_all();
    run_items();
    std::unique_lock<std::mutex> lock(mutex_);
    open_ = false;  // pool threads that have not joined yet stay out
    done_.wait(lock, [this] { return busy_ == 0; });
    if (error_) std::rethrow_exception(error_);
    return true;
  }

  ~ThreadPool() {
    {
      std::lock_guard<std::mutex> lock(mutex_);
      stop_ = true;
    }
    wake_.notify_all();
    for (auto& t : threads_) t.join();
  }

 private:
  ThreadPool() = default;

  void run_items() {
    in_loop() = true;
    try {
      for (std::size_t i = next_++; i < n_; i = next_++) call_(ctx_, i);
    } catch (...) {
      std::lock_guard<std::mutex> lock(error_mutex_);
      if (!error_) error_ = std::current_exception();
      next_ = n_;
    }
    in_loop() = false;
  }

  void worker(std::size_t index) {
    const AlternateSignalStack signal_stack;
    std::unique_lock<std::mutex> lock(mutex_);
    std::uint64_t seen = 0;
    for (;;) {
      wake_.wait(lock, [&] { return stop_ || generation_ != seen; });
      if (stop_) return;
      seen = generation_;
      if (!open_ || index >= helpers_) continue;
      ++busy_;
      lock.unlock();
      run_items();
      lock.lock();
      if (--busy_ == 0) done_.notify_all();
    }
  }

  std::mutex run_mutex_;  ///< held by the loop that uses the pool
  std::mutex mutex_;      ///< guards the fields below except next_ and error_
  std::mutex error_mutex_;
  std::condition_variable wake_, done_;
  std::vector<std::thread> threads_;
  std::uint64_t generation_ = 0;
  bool open_ = false, stop_ = false;
  std::size_t helpers_ = 0, busy_ = 0, n_ = 0;
  void* ctx_ = nullptr;
  Call call_ = nullptr;
  std::atomic<std::size_t> next_{0};
  std::exception_ptr error_;
};

}  // namespace detail

/// Calls f(i) for i in [0, n) on up to `threads` threads. Rethrows the first exception.
template <typename F>
void parallel_for(std::size_t n, int threads, F&& f) {
  const std::size_t workers = std::min<std::size_t>(n, static_cast<std::size_t>(std::max(threads, 1)));
  auto serial = [&] {
    for (std::size_t i = 0; i < n; ++i) f(i);
  };
  if (workers <= 1 || detail::ThreadPool::in_loop()) return serial();
  auto call = [](void* ctx, std::size_t i) { (*static_cast<std::remove_reference_t<F>*>(ctx))(i); };
  if (!detail::ThreadPool::instance().run(n, workers - 1, const_cast<void*>(static_cast<const void*>(&f)), call))
    serial();
}

}  // namespace vproxq
