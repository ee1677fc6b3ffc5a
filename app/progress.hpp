#pragma once
// "frame k/N, elapsed, ETA" on stderr for multi-frame runs in a terminal.
#include "core/timer.hpp"

#include <cstddef>

namespace vproxq {

class Progress {
 public:
  /// Shows nothing unless `enabled`, stderr is a terminal and there is more than one frame.
  Progress(std::size_t total, bool enabled);
  void update(std::size_t done);
  /// Erases the progress line (before other output to the terminal); update() redraws it.
  void clear();
  void finish();

 private:
  std::size_t total_;
  bool active_;
  bool dirty_ = false;
  Stopwatch clock_;
};

}  // namespace vproxq
