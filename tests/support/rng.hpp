#pragma once
// The tests' random numbers: one generator, the same on every platform and compiler (used by
// the suite's scene builders and by the fuzz replay driver, tests/fuzz/replay_main.cpp).
#include "core/types.hpp"

#include <cstdint>

namespace vproxq::test {

/// splitmix64: the same numbers on every platform (std distributions are not portable).
///
/// Draw order: C++ leaves unspecified the order in which the arguments of one call, or the
/// operands of one operator, are evaluated (GCC evaluates a call's arguments right to left,
/// clang left to right). Two draws in one such expression, e.g. `Vec3(rng.uniform(a, b),
/// rng.uniform(a, b), ...)`, would make the two compilers build different scenes, so the tests
/// draw in reading order: in separate statements, in braced lists (`Vec3{...}`, ordered by the
/// standard), or with vec3().
class Rng {
 public:
  explicit Rng(std::uint64_t seed) : s_(seed) {}
  std::uint64_t next() {
    std::uint64_t z = (s_ += 0x9e3779b97f4a7c15ULL);
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  }
  double uniform(double lo, double hi) { return lo + (hi - lo) * (next() >> 11) * 0x1.0p-53; }
  int integer(int lo, int hi) { return lo + static_cast<int>(next() % static_cast<std::uint64_t>(hi - lo + 1)); }
  /// A vector with each coordinate uniform in [lo, hi), drawn x, then y, then z: separate
  /// statements, so that GCC and clang build the same scenes (see above).
  Vec3 vec3(double lo, double hi) {
    const double x = uniform(lo, hi);
    const double y = uniform(lo, hi);
    const double z = uniform(lo, hi);
    return Vec3(x, y, z);
  }

 private:
  std::uint64_t s_;
};

}  // namespace vproxq::test
