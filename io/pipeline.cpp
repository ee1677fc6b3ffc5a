#include "io/pipeline.hpp"

#include "core/parallel.hpp"

#include <chrono>
#include <utility>

namespace vproxq {

void SerialWorker::run() {
  // Its own stack for the fatal-signal handler, as the pool threads have.
  const detail::AlternateSignalStack signal_stack;
  std::unique_lock<std::mutex> lock(mutex_);
  for (;;) {
    wake_.wait(lock, [this] { return stop_ || !queue_.empty(); });
    if (queue_.empty()) return;  // stop_, and nothing left
    std::packaged_task<void()> task = std::move(queue_.front());
    queue_.pop_front();
    lock.unlock();
    task();  // an exception goes to the task's future
    lock.lock();
  }
}

SerialWorker::~SerialWorker() {
  {
    const std::lock_guard<std::mutex> lock(mutex_);
    stop_ = true;
  }
  wake_.notify_one();
  if (thread_.joinable()) thread_.join();
}

namespace {

double ms_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

FrameReadAhead::FrameReadAhead(const SceneSource& scene, std::size_t first, std::size_t end, double inline_ms)
    : scene_(scene), next_(first), end_(end), inline_ms_(inline_ms) {}

Frame FrameReadAhead::read(std::size_t k) {
  const auto start = std::chrono::steady_clock::now();
  Frame frame = scene_.load_frame(k);
  last_ms_ = ms_since(start);
  return frame;
}

Frame FrameReadAhead::next() {
  // Read ahead (by the worker, or in line when reads are quick), or now.
  Frame frame = pending_.valid() ? pending_.get() : read(next_);  // rethrows the read's error
  ++next_;
  if (next_ < end_ && last_ms_ >= inline_ms_)
    pending_ = worker_.submit(std::packaged_task<Frame()>([this, k = next_] { return read(k); }));
  return frame;
}

FrameReadAhead::~FrameReadAhead() = default;  // the worker finishes a read still running

BackgroundWriter::BackgroundWriter(std::unique_ptr<ResultWriter> writer, double inline_ms)
    : writer_(std::move(writer)), inline_ms_(inline_ms) {}

void BackgroundWriter::wait() {
  if (pending_.valid()) pending_.get();  // rethrows the write's error
}

void BackgroundWriter::write_frame(FrameResult frame) {
  wait();
  if (last_ms_ < inline_ms_) {
    last_ms_ = writer_->write_frame(frame);
    return;
  }
  pending_ = worker_.submit(std::packaged_task<void()>([this, f = std::move(frame)] { last_ms_ = writer_->write_frame(f); }));
}

void BackgroundWriter::commit() {
  wait();
  writer_->commit();
}

BackgroundWriter::~BackgroundWriter() = default;  // the worker finishes a write still running

}  // namespace vproxq
