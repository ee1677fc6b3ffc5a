#pragma once
// Reading and writing beside the queries: the next frame is read on a background thread while
// the current one is computed (FrameReadAhead), and each frame's results are written on
// another while the next one is computed (BackgroundWriter). Both keep the order and the
// errors of doing the same in line: frames are read one at a time in sequence, only those the
// run would read anyway, and an error of a read or a write is rethrown, unchanged, where the
// run would have met it (a read's when its frame is asked for; a write's at the next write or
// at commit). No thread of either calls parallel_for (core/parallel.hpp): the queries keep the
// pool.
#include "io/output.hpp"
#include "io/scene_source.hpp"

#include <condition_variable>
#include <cstddef>
#include <deque>
#include <future>
#include <memory>
#include <mutex>
#include <thread>

namespace vproxq {

/// One background thread that runs the tasks given to it in order, started by the first
/// submit() (a run that keeps its reads and writes in line starts none) and joined (after the
/// tasks queued so far) by the destructor. Threads started per task
/// cost more than tiny frames do (1,000 frames of two 80-triangle blobs: 0.46 s on one thread
/// in line, 0.62 s with a thread per read and per write).
class SerialWorker {
 public:
  SerialWorker() = default;
  /// Queues `task`; its result (or exception) comes through the future.
  template <typename R>
  std::future<R> submit(std::packaged_task<R()> task) {
    std::future<R> result = task.get_future();
    {
      const std::lock_guard<std::mutex> lock(mutex_);
      queue_.emplace_back([t = std::move(task)]() mutable { t(); });
    }
    if (!thread_.joinable()) thread_ = std::thread([this] { run(); });
    wake_.notify_one();
    return result;
  }
  ~SerialWorker();

  SerialWorker(const SerialWorker&) = delete;
  SerialWorker& operator=(const SerialWorker&) = delete;

 private:
  void run();

  std::mutex mutex_;
  std::condition_variable wake_;
  std::deque<std::packaged_task<void()>> queue_;
  bool stop_ = false;
  std::thread thread_;
};

/// Reads and writes that took less than this (ms) are done in line: handing them to the
/// worker costs more than it hides (1,000 frames of two 80-triangle blobs, one thread: 0.45 s
/// in line, 0.51 s through the worker; funnel's frames take 7-9 ms to read, 6 to write).
inline constexpr double kInlineMs = 1.0;

/// Frames [first, end) of a scene, in order, each read while the previous one is in use.
class FrameReadAhead {
 public:
  /// `scene` must outlive this. `inline_ms`: see kInlineMs (0: every read but the first on
  /// the worker).
  FrameReadAhead(const SceneSource& scene, std::size_t first, std::size_t end, double inline_ms = kInlineMs);
  /// Frame `next_index()`; starts reading the one after it on the worker, unless this one
  /// took under `inline_ms` to read (then the next is read in line, when asked for). Rethrows
  /// the read's error. Must not be called past `end`.
  Frame next();
  std::size_t next_index() const { return next_; }
  /// Waits for a read still running (its result or error is dropped).
  ~FrameReadAhead();

  FrameReadAhead(const FrameReadAhead&) = delete;
  FrameReadAhead& operator=(const FrameReadAhead&) = delete;

 private:
  Frame read(std::size_t k);  ///< load_frame(k), timed into last_ms_

  const SceneSource& scene_;
  std::size_t next_, end_;
  double inline_ms_;
  double last_ms_ = 0;  ///< the last read's time (set before its future is ready)
  std::future<Frame> pending_;
  SerialWorker worker_;  // last: joined first, before what its task reads
};

/// A ResultWriter whose frames are written on a background thread, one at a time, in the
/// order given. `write_frame()` returns once the previous frame's write has finished and this
/// one's has been queued (or done in line, after a write that took under 1 ms).
class BackgroundWriter {
 public:
  /// `inline_ms`: see kInlineMs (0: every write on the worker).
  explicit BackgroundWriter(std::unique_ptr<ResultWriter> writer, double inline_ms = kInlineMs);
  /// Queues `frame` after waiting for the previous write; rethrows that write's error.
  void write_frame(FrameResult frame);
  /// Waits for the last write (rethrowing its error), then commits.
  void commit();
  /// Waits for a write still running; without commit(), the files are removed (ResultWriter).
  ~BackgroundWriter();

  BackgroundWriter(const BackgroundWriter&) = delete;
  BackgroundWriter& operator=(const BackgroundWriter&) = delete;

 private:
  void wait();

  std::unique_ptr<ResultWriter> writer_;
  double inline_ms_;
  double last_ms_ = 0;  ///< the last write's time (set before its future is ready)
  std::future<void> pending_;
  SerialWorker worker_;  // last: joined first, before the writer is destroyed
};

}  // namespace vproxq
