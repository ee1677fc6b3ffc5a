#include "io/pipeline.hpp"

#include "core/parallel.hpp"

#include <utility>

namespace vproxq {

FrameReadAhead::FrameReadAhead(const SceneSource& scene, std::size_t first, std::size_t end)
    : scene_(scene), next_(first), end_(end) {
  start();
}

void FrameReadAhead::start() {
  if (next_ >= end_) return;
  pending_ = std::async(std::launch::async, [this, k = next_] {
    // Its own stack for the fatal-signal handler, as the pool threads have.
    const detail::AlternateSignalStack signal_stack;
    return scene_.load_frame(k);
  });
}

Frame FrameReadAhead::next() {
  Frame frame = pending_.get();  // rethrows the read's error
  ++next_;
  start();
  return frame;
}

FrameReadAhead::~FrameReadAhead() {
  if (pending_.valid()) pending_.wait();
}

BackgroundWriter::BackgroundWriter(std::unique_ptr<ResultWriter> writer) : writer_(std::move(writer)) {}

void BackgroundWriter::wait() {
  if (pending_.valid()) pending_.get();  // rethrows the write's error
}

void BackgroundWriter::write_frame(FrameResult frame) {
  wait();
  pending_ = std::async(std::launch::async, [this, f = std::move(frame)] {
    const detail::AlternateSignalStack signal_stack;
    writer_->write_frame(f);
  });
}

void BackgroundWriter::commit() {
  wait();
  writer_->commit();
}

BackgroundWriter::~BackgroundWriter() {
  if (pending_.valid()) pending_.wait();
}

}  // namespace vproxq
