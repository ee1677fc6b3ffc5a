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

#include <cstddef>
#include <future>
#include <memory>

namespace vproxq {

/// Frames [first, end) of a scene, in order, each read while the previous one is in use.
class FrameReadAhead {
 public:
  /// Starts reading frame `first` (when first < end). `scene` must outlive this.
  FrameReadAhead(const SceneSource& scene, std::size_t first, std::size_t end);
  /// Frame `next_index()`; starts reading the one after it. Rethrows the read's error.
  /// Must not be called past `end`.
  Frame next();
  std::size_t next_index() const { return next_; }
  /// Waits for a read still running (its result or error is dropped).
  ~FrameReadAhead();

  FrameReadAhead(const FrameReadAhead&) = delete;
  FrameReadAhead& operator=(const FrameReadAhead&) = delete;

 private:
  void start();

  const SceneSource& scene_;
  std::size_t next_, end_;
  std::future<Frame> pending_;
};

/// A ResultWriter whose frames are written on a background thread, one at a time, in the
/// order given. `write_frame()` returns once the previous frame's write has finished and this
/// one's has started.
class BackgroundWriter {
 public:
  explicit BackgroundWriter(std::unique_ptr<ResultWriter> writer);
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
  std::future<void> pending_;  // declared after writer_: destroyed (waited for) first
};

}  // namespace vproxq
