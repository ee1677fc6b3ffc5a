#pragma once
// What the fuzz harnesses share: a scratch directory of their own and a check that stops the
// fuzzer (a crash it records, with the input) instead of throwing.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <string>

namespace vproxq::fuzz {

/// A directory of this process's own, made on first use and removed when the process exits.
const std::filesystem::path& scratch_dir();

/// Writes `size` bytes to `file`, replacing it.
void write_file(const std::filesystem::path& file, const void* data, std::size_t size);

/// The input's bytes one at a time, then zeros once they run out (the harnesses that decode
/// their inputs into numbers).
struct ByteReader {
  const std::uint8_t* data;
  std::size_t size, at = 0;
  std::uint8_t next() { return at < size ? data[at++] : 0; }
};

}  // namespace vproxq::fuzz

#define VPROXQ_FUZZ_CHECK(cond)                                                               \
  do {                                                                                        \
    if (!(cond)) {                                                                            \
      std::fprintf(stderr, "check failed: %s (%s:%d)\n", #cond, __FILE__, __LINE__);         \
      __builtin_trap();                                                                       \
    }                                                                                         \
  } while (0)
