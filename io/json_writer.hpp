#pragma once
// Internal to io/: writes results.json frame by frame, so that memory does not grow with the
// number of frames. Used by ResultWriter (io/output.cpp); the keys are fixed by DESIGN.md
// ("Output") and documented in the README.
#include "core/results.hpp"

#include <nlohmann/json.hpp>

#include <cstdio>
#include <filesystem>
#include <memory>
#include <string>

namespace vproxq::detail {

/// The top-level members of results.json that precede "frames", in file order.
nlohmann::ordered_json run_header_json(const RunInfo& info);

/// One entry of "frames", in file order; stats.time_ms.write is `write_ms`, not
/// frame.time_ms.write.
nlohmann::ordered_json frame_json(const FrameResult& frame, double write_ms);

/// Diff-friendly text of `value`: an array holding objects, and an object holding such an
/// array (at any depth), are spread one member per line with one space of indent per level;
/// everything else is written compactly on one line (one line per object, per inter record).
/// Doubles are written in nlohmann's shortest round-trip form; invalid UTF-8 is replaced.
std::string format_json(const nlohmann::ordered_json& value, int indent);

/// results.json under construction: the header is written on open, each frame is appended
/// as it comes (always spread one member per line, as format_json spreads), and close() ends
/// the document. Only the frame being written is held in memory.
class JsonResultStream {
 public:
  /// Creates (truncates) `file` and writes the header. Throws RuntimeError naming the file.
  JsonResultStream(const std::filesystem::path& file, const RunInfo& info);
  /// Appends one frame. Throws RuntimeError naming the file and strerror.
  void write_frame(const FrameResult& frame, double write_ms);
  /// Ends the document, flushes it to disk (fsync) and closes the file. Throws RuntimeError.
  void close();
  /// Closes the file if still open (without ending the document); never removes it.
  ~JsonResultStream();

  JsonResultStream(const JsonResultStream&) = delete;
  JsonResultStream& operator=(const JsonResultStream&) = delete;

 private:
  struct FileCloser {
    void operator()(std::FILE* f) const { std::fclose(f); }
  };

  void put(const std::string& text);
  [[noreturn]] void fail(const char* what, int error) const;

  std::filesystem::path path_;
  std::unique_ptr<std::FILE, FileCloser> file_;
  std::size_t frames_written_ = 0;
};

}  // namespace vproxq::detail
