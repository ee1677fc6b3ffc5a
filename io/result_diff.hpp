#pragma once
// `vproxq diff`: compares two results.json files, ignoring what may differ between runs.
#include <filesystem>
#include <string>
#include <vector>

namespace vproxq {

struct DiffOptions {
  double rtol = 0.0;  ///< numbers a, b are equal when |a-b| <= atol + rtol*max(|a|,|b|)
  double atol = 0.0;
  /// Member names left out wherever they occur, at any depth (`--ignore`): e.g. a key added
  /// in a later version, compared across versions.
  std::vector<std::string> ignore;
};

struct DiffOutcome {
  bool equal = true;
  std::string first_difference;  ///< e.g. "frame 3, distance.inter[2].distance: 0.5 vs 0.25"
};

/// Compares everything but "stats" (per frame), "version", "settings" and the members named in
/// opts.ignore; objects key by key,
/// arrays element by element, numbers with the tolerances. Throws InputError for a missing or
/// malformed file.
DiffOutcome diff_result_files(const std::filesystem::path& a, const std::filesystem::path& b,
                              const DiffOptions& opts);

}  // namespace vproxq
