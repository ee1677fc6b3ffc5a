#pragma once
// Result files: OUT/results.json (summary) and OUT/results.h5 (full detail), written frame by
// frame into temporary files that are renamed into place only by commit().
#include "core/results.hpp"

#include <filesystem>
#include <memory>

namespace vproxq {

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
