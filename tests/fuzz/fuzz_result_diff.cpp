// `vproxq diff` on two inputs (the bytes before and after the first 0xff byte, as two
// results.json files; seed it with results.json files of runs joined that way): an InputError,
// or an answer that is symmetric, and a file is always equal to itself.
#include "core/errors.hpp"
#include "fuzz_support.hpp"
#include "io/result_diff.hpp"

#include <algorithm>
#include <cstddef>
#include <cstdint>

using namespace vproxq;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::uint8_t* split = std::find(data, data + size, 0xff);
  const auto a = fuzz::scratch_dir() / "a.json";
  const auto b = fuzz::scratch_dir() / "b.json";
  fuzz::write_file(a, data, static_cast<std::size_t>(split - data));
  const std::uint8_t* rest = split == data + size ? split : split + 1;
  fuzz::write_file(b, rest, static_cast<std::size_t>(data + size - rest));
  DiffOptions opts;
  opts.rtol = size > 0 && data[0] % 2 ? 1e-9 : 0.0;
  try {
    VPROXQ_FUZZ_CHECK(diff_result_files(a, a, opts).equal);
    const DiffOutcome ab = diff_result_files(a, b, opts);
    const DiffOutcome ba = diff_result_files(b, a, opts);
    VPROXQ_FUZZ_CHECK(ab.equal == ba.equal);
    VPROXQ_FUZZ_CHECK(ab.equal == ab.first_difference.empty());
  } catch (const InputError&) {
  }
  return 0;
}
