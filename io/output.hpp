#pragma once
// Result files: OUT/results.json (summary) and OUT/results.h5 (full detail), written frame by
// frame into temporary files that are renamed into place only by commit().
#include "core/results.hpp"

#include <filesystem>
#include <memory>
#include <string>

namespace vproxq {

/// `text` as valid UTF-8: invalid byte sequences replaced by U+FFFD, as results.json, results.h5
/// and the summary on stdout write names and paths (nlohmann's error_handler_t::replace), so
/// that all three hold the same strings.
std::string valid_utf8(const std::string& text);

class ResultWriter {
 public:
  /// Creates `out_dir` if needed and opens the temporary files. Throws RuntimeError.
  ResultWriter(const std::filesystem::path& out_dir, const RunInfo& info);
  /// Appends one frame to both files; returns the milliseconds it took. Throws RuntimeError.
  double write_frame(const FrameResult& frame);
  /// Closes both files and renames them into place. Throws RuntimeError.
  void commit();
  /// Without commit(), the destructor removes the temporary files: no partial output.
  ~ResultWriter();

  ResultWriter(const ResultWriter&) = delete;
  ResultWriter& operator=(const ResultWriter&) = delete;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vproxq
