// Exact dyadic arithmetic against 128-bit integers and powers of two at the ends of the
// coordinate range; exact point-triangle squared distances against constructions whose
// distance is known exactly, and against the double-precision point_triangle_distance within
// its documented error.
#include "core/geometry/exact_distance.hpp"
#include "core/geometry/point_triangle.hpp"
#include "support/rng.hpp"

#include <gtest/gtest.h>

#include <cmath>

namespace vproxq {
namespace {

using test::Rng;
__extension__ using Int128 = __int128;
__extension__ using UInt128 = unsigned __int128;

/// The exact value of a 128-bit integer as a Dyadic (built from two exact halves).
Dyadic dyadic_of(Int128 v) {
  const bool negative = v < 0;
  const UInt128 m = negative ? -static_cast<UInt128>(v) : static_cast<UInt128>(v);
  const Dyadic hi(std::ldexp(static_cast<double>(static_cast<std::uint64_t>(m >> 64) >> 32), 96));
  const Dyadic mid(std::ldexp(static_cast<double>(static_cast<std::uint32_t>(m >> 64)), 64));
  const Dyadic lo_hi(std::ldexp(static_cast<double>(static_cast<std::uint32_t>(m >> 32)), 32));
  const Dyadic lo(static_cast<double>(static_cast<std::uint32_t>(m)));
  const Dyadic sum = hi + mid + lo_hi + lo;
  return negative ? -sum : sum;
}

TEST(Dyadic, MatchesIntegerArithmetic) {
  Rng rng(41);
  // Integers below 2^53 in magnitude (exact as doubles), drawn one by one (see Rng).
  auto draw = [&] {
    const int shift = rng.integer(11, 63);
    const auto m = static_cast<std::int64_t>(rng.next() >> shift);
    return rng.integer(0, 1) ? m : -m;
  };
  for (int trial = 0; trial < 20000; ++trial) {
    const std::int64_t a = draw(), b = draw(), c = draw();
    const Dyadic da(static_cast<double>(a)), db(static_cast<double>(b)), dc(static_cast<double>(c));
    const Int128 ab = static_cast<Int128>(a) * b;
    EXPECT_EQ(compare(da * db, dyadic_of(ab)), 0) << a << " * " << b;
    EXPECT_EQ(compare(da * db - dc, dyadic_of(ab - c)), 0);
    EXPECT_EQ((da * db - dc).sign(), (ab > c) - (ab < c));
    EXPECT_EQ(compare(da + db, dyadic_of(static_cast<Int128>(a) + b)), 0);
    EXPECT_EQ(compare(da, db), (a > b) - (a < b));
  }
}

TEST(Dyadic, ExactAcrossTheCoordinateRange) {
  const Dyadic big(0x1p199), small(0x1p-200), one(1.0);
  // (2^199 + 2^-200) - 2^199 = 2^-200: no rounding, whatever the spread of exponents.
  EXPECT_EQ(compare((big + small) - big, small), 0);
  EXPECT_EQ(((big + small) - big).sign(), 1);
  EXPECT_EQ(compare(big * small, Dyadic(0.5)), 0);
  // Ten factors of 2^199 (2^1990, far beyond double's range) against 2^1990 + 2^-2000.
  Dyadic p10 = one, q10 = one;
  for (int k = 0; k < 10; ++k) {
    p10 = p10 * big;
    q10 = q10 * small;
  }
  EXPECT_EQ(compare(p10 + q10, p10), 1);
  EXPECT_EQ(compare(p10 - q10, p10), -1);
  EXPECT_EQ((p10 - p10).sign(), 0);
  EXPECT_EQ(compare(Dyadic(-0.0), Dyadic()), 0);
  EXPECT_EQ(compare(Dyadic(-3.5) * Dyadic(-2.0), Dyadic(7.0)), 0);
  // Non-dyadic decimals are their exact doubles: 0.1 + 0.2 != 0.3, but 0.5 + 0.25 == 0.75.
  EXPECT_NE(compare(Dyadic(0.1) + Dyadic(0.2), Dyadic(0.3)), 0);
  EXPECT_EQ(compare(Dyadic(0.5) + Dyadic(0.25), Dyadic(0.75)), 0);
}

/// Whether the exact squared distance equals x * x exactly.
bool squared_is(const ExactFraction& f, double x) {
  return compare(f, ExactFraction{Dyadic(x) * Dyadic(x), Dyadic(1.0)}) == 0;
}

// Right triangles on the plane z = z0 with dyadic corners (a random offset and scale): a point
// at height h over the inside is h away, over an edge's outside √(g² + h²), past a corner
// √(gx² + gy² + h²), all exact dyadic; and the triangle's degenerate forms.
TEST(ExactPointTriangle, KnownDistances) {
  Rng rng(7);
  for (int trial = 0; trial < 3000; ++trial) {
    const double s = std::ldexp(1.0, rng.integer(-60, 60));
    const Vec3 o = s * Vec3{static_cast<double>(rng.integer(-1000, 1000)), static_cast<double>(rng.integer(-1000, 1000)),
                            static_cast<double>(rng.integer(-1000, 1000))};
    const double a = s * rng.integer(4, 64), b = s * rng.integer(4, 64);
    const Triangle t{o, o + Vec3(a, 0, 0), o + Vec3(0, b, 0)};
    const double h = s * rng.integer(0, 64) / 8.0;
    // Over the inside: x, y > 0, x/a + y/b < 1 (both below a quarter of the legs).
    const double x = a * rng.integer(1, 7) / 32.0, y = b * rng.integer(1, 7) / 32.0;
    EXPECT_TRUE(squared_is(exact_point_triangle_squared_distance(o + Vec3(x, y, h), t), h));
    // Beyond the edge y = 0, over its middle part: g² + h² with g the gap below it.
    const double g = s * rng.integer(1, 64) / 4.0;
    const ExactFraction beyond = exact_point_triangle_squared_distance(o + Vec3(x, -g, h), t);
    EXPECT_EQ(compare(beyond, ExactFraction{Dyadic(g) * Dyadic(g) + Dyadic(h) * Dyadic(h), Dyadic(1.0)}), 0);
    // Past the corner o.
    const double gx = s * rng.integer(1, 64) / 4.0;
    const ExactFraction past = exact_point_triangle_squared_distance(o + Vec3(-gx, -g, h), t);
    EXPECT_EQ(compare(past, ExactFraction{Dyadic(gx) * Dyadic(gx) + Dyadic(g) * Dyadic(g) + Dyadic(h) * Dyadic(h),
                                          Dyadic(1.0)}),
              0);
    // A collinear triangle is its longest edge; a point triangle its corner.
    const Triangle line{o, o + Vec3(a, 0, 0), o + Vec3(2 * a, 0, 0)};
    EXPECT_TRUE(squared_is(exact_point_triangle_squared_distance(o + Vec3(x, 0, h), line), h));
    const Triangle point{o, o, o};
    EXPECT_EQ(compare(exact_point_triangle_squared_distance(o + Vec3(gx, g, h), point),
                      ExactFraction{Dyadic(gx) * Dyadic(gx) + Dyadic(g) * Dyadic(g) + Dyadic(h) * Dyadic(h), Dyadic(1.0)}),
              0);
  }
}

// On random (non-dyadic) points and triangles, needles included, the exact squared distance
// lies within 16 e*S of point_triangle_distance's (the bound in docs/algorithms.md, S the largest coordinate
// magnitude), and two distances whose computed values differ by more than that are ordered as
// computed.
TEST(ExactPointTriangle, AgreesWithDoublePrecisionWithinItsError) {
  Rng rng(11);
  for (int trial = 0; trial < 4000; ++trial) {
    const double scale = std::ldexp(1.0, rng.integer(-30, 30));
    const Vec3 offset = rng.vec3(-1, 1) * (trial % 3 == 0 ? 1e3 * scale : 0.0);
    Triangle t{offset + scale * rng.vec3(-1, 1), offset + scale * rng.vec3(-1, 1), offset + scale * rng.vec3(-1, 1)};
    if (trial % 5 == 0) t[2] = t[0] + 1e-9 * (t[2] - t[0]);  // a needle
    const Vec3 p = offset + scale * rng.vec3(-1.5, 1.5);
    double big = p.cwiseAbs().maxCoeff();
    for (const Vec3& c : t) big = std::max(big, c.cwiseAbs().maxCoeff());
    const double err = 16 * 0x1p-53 * big;
    const double d = std::sqrt(point_triangle_distance(p, t).squared_distance);
    const double lo = std::max(0.0, d - err), hi = d + err;
    const ExactFraction exact = exact_point_triangle_squared_distance(p, t);
    EXPECT_GE(compare(exact, ExactFraction{Dyadic(lo) * Dyadic(lo), Dyadic(1.0)}), 0) << trial;
    EXPECT_LE(compare(exact, ExactFraction{Dyadic(hi) * Dyadic(hi), Dyadic(1.0)}), 0) << trial;
    const Vec3 q = offset + scale * rng.vec3(-1.5, 1.5);
    double big_q = big;
    big_q = std::max(big_q, q.cwiseAbs().maxCoeff());
    const double dq = std::sqrt(point_triangle_distance(q, t).squared_distance);
    if (std::fabs(d - dq) > 2 * 16 * 0x1p-53 * big_q) {
      EXPECT_EQ(compare(exact, exact_point_triangle_squared_distance(q, t)), d < dq ? -1 : 1) << trial;
    }
  }
}

}  // namespace
}  // namespace vproxq
