// Fuzzing the distance primitives (triangle_distance, point_triangle_distance,
// segment_segment_distance) and the exact intersection decision against triangle pairs whose
// distance is known exactly: each input decodes, integer by integer, into the slab
// construction of tests/support/slab_pair.hpp (needles, caps, repeated and collinear corners,
// corners on the other triangle's edges, parallel features, touching and just-apart pairs,
// coordinates up to 2^52 times 2^[-60, 60]). What must hold is check_slab_pair's: touching
// exactly when the construction touches, the slab's width when the top features meet and at
// least that otherwise, within 16 e*S, for both argument orders and all 15 feature pairs.
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string>

#include "fuzz_support.hpp"
#include "support/slab_pair.hpp"

using namespace vproxq;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  fuzz::ByteReader in{data, size};
  // An integer in [lo, hi] from as many bytes as the range needs (zeros past the end).
  auto pick = [&](std::int64_t lo, std::int64_t hi) {
    const auto range = static_cast<std::uint64_t>(hi - lo) + 1;
    std::uint64_t value = 0, capacity = 1;
    while (capacity < range) {
      value = value * 256 + in.next();
      capacity *= 256;
    }
    return lo + static_cast<std::int64_t>(value % range);
  };
  const test::SlabPair pair = test::make_slab_pair(pick);
  const std::string failure = test::check_slab_pair(pair);
  if (!failure.empty()) std::fprintf(stderr, "%s\n%s\n", failure.c_str(), pair.recipe.c_str());
  VPROXQ_FUZZ_CHECK(failure.empty());
  return 0;
}
