#pragma once
// Error kinds, each mapped to a documented exit code by the CLI (see README, "Exit codes").
#include <stdexcept>
#include <string>

namespace vproxq {

/// Bad command line or option value. Exit code 2.
struct UsageError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
/// Bad input data: missing or malformed scene or mesh file, NaN coordinate, ... Exit code 3.
/// The message names the file and the problem.
struct InputError : std::runtime_error {
  using std::runtime_error::runtime_error;
};
/// Failure while running (cannot write output, GPU context lost, ...). Exit code 4.
struct RuntimeError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

namespace exit_code {
inline constexpr int kOk = 0;
inline constexpr int kDifferent = 1;  ///< `vproxq diff`: the files differ
inline constexpr int kUsage = 2;
inline constexpr int kInput = 3;
inline constexpr int kRuntime = 4;
}  // namespace exit_code

}  // namespace vproxq
