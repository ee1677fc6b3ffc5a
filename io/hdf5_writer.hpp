#pragma once
// Internal to io/: writes results.h5 (full detail) frame by frame through the HDF5 C API.
// Used by ResultWriter (io/output.cpp); the layout is documented in the README, "results.h5".
#include "core/results.hpp"

#include <chrono>
#include <cstdint>
#include <filesystem>
#include <memory>

namespace vproxq::detail {

/// Value of the `case` field of /frames/NNNNNN/distance/inter for an object with no other
/// object in the frame (its nearest_object is -1).
inline constexpr std::uint8_t kHdf5CaseNone = 255;

class Hdf5ResultWriter {
 public:
  /// Creates (truncates) `file` and writes the root attributes. Throws RuntimeError naming the
  /// HDF5 call and the file.
  Hdf5ResultWriter(const std::filesystem::path& file, const RunInfo& info);
  /// Writes group /frames/NNNNNN (NNNNNN: frame.frame, 6 digits). The milliseconds elapsed
  /// since `started` once everything but the stats group is written are recorded there as
  /// time_ms_write, and returned.
  double write_frame(const FrameResult& frame, std::chrono::steady_clock::time_point started);
  /// Closes the file, checking every close. Throws RuntimeError.
  void close();
  /// Closes whatever is still open, ignoring errors; never removes the file.
  ~Hdf5ResultWriter();

  Hdf5ResultWriter(const Hdf5ResultWriter&) = delete;
  Hdf5ResultWriter& operator=(const Hdf5ResultWriter&) = delete;

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
};

}  // namespace vproxq::detail
