#pragma once
// Arithmetic that gives bit-identical results on every IEEE-754 machine, so that a generator
// run with the same seed writes byte-identical files everywhere:
//  - a seeded PRNG (SplitMix64 seeding xoshiro256**) instead of std::uniform_*_distribution,
//    whose output is not specified by the standard and differs between libraries;
//  - a sine built from +, -, *, / and nearbyint only, instead of std::sin, whose last bit
//    differs between C libraries;
//  - a 3-vector whose operations have a fixed evaluation order.
// Build with -ffp-contract=off (sample_scenes/CMakeLists.txt does): a fused multiply-add
// rounds once instead of twice and would change the output on machines that contract.
#include <cmath>
#include <cstdint>

namespace vproxq::gen {

struct V3 {
  double x = 0, y = 0, z = 0;
};
inline V3 operator+(const V3& a, const V3& b) { return {a.x + b.x, a.y + b.y, a.z + b.z}; }
inline V3 operator-(const V3& a, const V3& b) { return {a.x - b.x, a.y - b.y, a.z - b.z}; }
inline V3 operator*(double s, const V3& a) { return {s * a.x, s * a.y, s * a.z}; }
inline double dot(const V3& a, const V3& b) { return (a.x * b.x + a.y * b.y) + a.z * b.z; }
inline V3 cross(const V3& a, const V3& b) {
  return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
/// a / |a| (sqrt and division are correctly rounded by IEEE 754, hence deterministic).
inline V3 normalized(const V3& a) {
  const double n = std::sqrt(dot(a, a));
  return {a.x / n, a.y / n, a.z / n};
}

/// SplitMix64 (Steele, Lea, Flood 2014): advances `state` and returns a well-mixed word.
inline std::uint64_t splitmix64(std::uint64_t& state) {
  std::uint64_t z = (state += 0x9E3779B97F4A7C15ull);
  z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
  z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
  return z ^ (z >> 31);
}

/// xoshiro256** 1.0 (Blackman, Vigna 2018). One independent stream per (seed, stream id),
/// so that what one object draws does not depend on how many objects came before it.
class Rng {
 public:
  Rng(std::uint64_t seed, std::uint64_t stream) {
    std::uint64_t sm = seed;
    std::uint64_t mix = splitmix64(sm);
    std::uint64_t st = stream;
    mix ^= splitmix64(st);
    for (auto& word : s_) word = splitmix64(mix);
  }

  std::uint64_t next() {
    const std::uint64_t result = rotl(s_[1] * 5, 7) * 9;
    const std::uint64_t t = s_[1] << 17;
    s_[2] ^= s_[0];
    s_[3] ^= s_[1];
    s_[1] ^= s_[2];
    s_[0] ^= s_[3];
    s_[2] ^= t;
    s_[3] = rotl(s_[3], 45);
    return result;
  }

  /// Uniform in [0, 1): the top 53 bits scaled by 2^-53 (exact).
  double uniform() { return static_cast<double>(next() >> 11) * 0x1.0p-53; }
  /// Uniform in [lo, hi).
  double uniform(double lo, double hi) { return lo + (hi - lo) * uniform(); }
  /// Uniform direction: rejection sampling in the cube [-1, 1]^3, then normalized.
  V3 unit_vector() {
    for (;;) {
      const V3 p{uniform(-1, 1), uniform(-1, 1), uniform(-1, 1)};
      const double n2 = dot(p, p);
      // Reject the corners (not uniform) and points so close to 0 that the direction is noise.
      if (n2 <= 1.0 && n2 > 1e-6) return normalized(p);
    }
  }

 private:
  static std::uint64_t rotl(std::uint64_t x, int k) { return (x << k) | (x >> (64 - k)); }
  std::uint64_t s_[4] = {};
};

inline constexpr double kPi = 3.14159265358979311600e+00;  // pi rounded to double
inline constexpr double kPiLo = 1.22464679914735317723e-16;  // pi - kPi
inline constexpr double kTwoPi = 2 * kPi;                      // exact (power-of-two scaling)
inline constexpr double kTwoPiLo = 2 * kPiLo;
inline constexpr double kHalfPi = 0.5 * kPi;

/// sin(x), identical on every IEEE-754 machine. Absolute error about 1e-16 (1 + |x|)
/// (measured against glibc: 5e-16 for |x| < 2, 1.3e-14 for |x| < 100); the generators'
/// arguments stay below 20.
/// Range reduction to [-pi, pi] with a two-part 2*pi (Cody-Waite), folding to [-pi/2, pi/2],
/// then the Taylor series to x^21 (truncation error < 3e-17 on [-pi/2, pi/2]).
inline double det_sin(double x) {
  const double k = std::nearbyint(x / kTwoPi);
  double r = (x - k * kTwoPi) - k * kTwoPiLo;
  if (r > kHalfPi) r = (kPi - r) + kPiLo;  // sin(r) = sin(pi - r)
  else if (r < -kHalfPi) r = (-kPi - r) - kPiLo;
  const double r2 = r * r;
  double p = 1.0 / 51090942171709440000.0;  // 1/21!
  p = p * r2 - 1.0 / 121645100408832000.0;  // 1/19!
  p = p * r2 + 1.0 / 355687428096000.0;     // 1/17!
  p = p * r2 - 1.0 / 1307674368000.0;       // 1/15!
  p = p * r2 + 1.0 / 6227020800.0;          // 1/13!
  p = p * r2 - 1.0 / 39916800.0;            // 1/11!
  p = p * r2 + 1.0 / 362880.0;              // 1/9!
  p = p * r2 - 1.0 / 5040.0;                // 1/7!
  p = p * r2 + 1.0 / 120.0;                 // 1/5!
  p = p * r2 - 1.0 / 6.0;                   // 1/3!
  return r + r * (r2 * p);
}

/// cos(x) = sin(x + pi/2), with the same guarantees as det_sin.
inline double det_cos(double x) { return det_sin(x + kHalfPi); }

}  // namespace vproxq::gen
