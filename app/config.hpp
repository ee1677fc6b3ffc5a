#pragma once
// Everything a run needs, filled by the CLI (app/cli.cpp) and consumed by run().
#include <optional>
#include <string>
#include <vector>

namespace vproxq {

struct FrameRange {
  std::optional<long> first;  ///< inclusive, 0-based position; default 0
  std::optional<long> last;   ///< exclusive; default: end of sequence
};

struct Config {
  std::string scene_path;
  std::vector<std::string> queries;  ///< empty: scene.json's list, else {"distance"}
  std::string output_dir;            ///< empty: no files written
  FrameRange frames;
  std::string voronoi = "off";  ///< off | cpu | gpu | auto (see README: off is fastest today)
  int grid = 0;                  ///< cells along the longest axis; 0: scene's "grid", else automatic
  int ccd_grid = 0;              ///< CCD's Stage II grid, cells along the longest axis; 0: automatic
  int device = -1;               ///< EGL device index for gpu; -1: prefer a hardware device
  int threads = 0;               ///< 0: all hardware threads
  std::optional<bool> self;      ///< the distance query's intra-object part; unset: scene's "self", else on
  bool quiet = false;
};

/// Runs the queries of `config` frame by frame and writes the outputs. Throws UsageError,
/// InputError or RuntimeError (core/errors.hpp); never leaves partial output files.
void run(const Config& config);

}  // namespace vproxq
