#include "app/progress.hpp"

#include <cstdio>
#include <unistd.h>

namespace vproxq {

Progress::Progress(std::size_t total, bool enabled)
    : total_(total), active_(enabled && total > 1 && isatty(fileno(stderr))) {}

void Progress::update(std::size_t done) {
  if (!active_) return;
  const double elapsed = clock_.elapsed_ms() / 1000.0;
  const double eta = done > 0 ? elapsed / static_cast<double>(done) * static_cast<double>(total_ - done) : 0.0;
  std::fprintf(stderr, "\rframe %zu/%zu  elapsed %.1fs  ETA %.1fs   ", done, total_, elapsed, eta);
  std::fflush(stderr);
  dirty_ = true;
}

void Progress::clear() {
  if (!active_ || !dirty_) return;
  std::fprintf(stderr, "\r%*s\r", 60, "");
  std::fflush(stderr);
  dirty_ = false;
}

void Progress::finish() {
  if (active_ && dirty_) std::fprintf(stderr, "\n");
  dirty_ = false;
}

}  // namespace vproxq
