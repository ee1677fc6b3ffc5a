#pragma once
// What the fuzz harnesses share: a scratch directory of their own and a check that stops the
// fuzzer (a crash it records, with the input) instead of throwing.
#include <cstdio>
#include <filesystem>
#include <string>

namespace vproxq::fuzz {

/// A directory of this process's own, made on first use and removed when the process exits.
const std::filesystem::path& scratch_dir();

/// Writes `size` bytes to `file`, replacing it.
void write_file(const std::filesystem::path& file, const void* data, std::size_t size);

}  // namespace vproxq::fuzz

#define VPROXQ_FUZZ_CHECK(cond)                                                               \
  do {                                                                                        \
    if (!(cond)) {                                                                            \
      std::fprintf(stderr, "check failed: %s (%s:%d)\n", #cond, __FILE__, __LINE__);         \
      __builtin_trap();                                                                       \
    }                                                                                         \
  } while (0)
