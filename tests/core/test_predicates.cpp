// Tests of the exact orientation predicates against an independent exact twin: every double is
// an integer times a power of two, so the determinants are dyadic rationals, evaluated here in
// exact arbitrary-precision arithmetic (Dyadic).
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <random>
#include <vector>

#include "core/geometry/exact_distance.hpp"
#include "core/geometry/predicates.hpp"

namespace vproxq {
namespace {

// ---- the twin: exact dyadic arithmetic ---------------------------------------------------
// Every double is a dyadic rational, and so are the determinants of doubles: Dyadic
// (core/geometry/exact_distance.hpp, tested against 128-bit integers in test_exact_distance)
// evaluates them exactly, with no floating-point filter and no expansions.

int exact_orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  Dyadic u[3], v[3], w[3];
  for (int k = 0; k < 3; ++k) {
    u[k] = Dyadic(b[k]) - Dyadic(a[k]);
    v[k] = Dyadic(c[k]) - Dyadic(a[k]);
    w[k] = Dyadic(d[k]) - Dyadic(a[k]);
  }
  const Dyadic det = u[0] * (v[1] * w[2] - v[2] * w[1]) + u[1] * (v[2] * w[0] - v[0] * w[2]) +
                     u[2] * (v[0] * w[1] - v[1] * w[0]);
  return det.sign();
}

int exact_orient2d(const Vec2& a, const Vec2& b, const Vec2& c) {
  const Dyadic det = (Dyadic(b[0]) - Dyadic(a[0])) * (Dyadic(c[1]) - Dyadic(a[1])) -
                     (Dyadic(b[1]) - Dyadic(a[1])) * (Dyadic(c[0]) - Dyadic(a[0]));
  return det.sign();
}

/// Plain double evaluation, to show the adversarial inputs really defeat it.
int naive_orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double det = (b - a).cross(c - a).dot(d - a);
  return (det > 0) - (det < 0);
}
int naive_orient2d(const Vec2& a, const Vec2& b, const Vec2& c) {
  const double det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);
  return (det > 0) - (det < 0);
}

__extension__ typedef __int128 Int128;  // GCC/Clang extension, test-only

int sign_of_int128(Int128 v) { return (v > 0) - (v < 0); }

Int128 int_orient3d(const std::array<std::int64_t, 12>& p) {
  const Int128 ux = p[3] - p[0], uy = p[4] - p[1], uz = p[5] - p[2];
  const Int128 vx = p[6] - p[0], vy = p[7] - p[1], vz = p[8] - p[2];
  const Int128 wx = p[9] - p[0], wy = p[10] - p[1], wz = p[11] - p[2];
  return ux * (vy * wz - vz * wy) + uy * (vz * wx - vx * wz) + uz * (vx * wy - vy * wx);
}

Vec3 random_point(std::mt19937_64& rng, double half_size, double offset = 0.0) {
  std::uniform_real_distribution<double> u(-half_size, half_size);
  return Vec3{offset + u(rng), offset + u(rng), offset + u(rng)};
}

/// x moved by `steps` ulps (toward +inf when positive).
double ulp_step(double x, int steps) {
  for (int i = 0; i < std::abs(steps); ++i) {
    x = std::nextafter(x, steps > 0 ? kInfinity : -kInfinity);
  }
  return x;
}

// ---- tests ----------------------------------------------------------------------------------

TEST(ExactTwin, AgreesWithInt128OnSmallIntegers) {
  std::mt19937_64 rng(1);
  std::uniform_int_distribution<std::int64_t> coord(-(std::int64_t{1} << 40), std::int64_t{1} << 40);
  for (int trial = 0; trial < 2000; ++trial) {
    std::array<std::int64_t, 12> p{};
    for (auto& x : p) x = coord(rng);
    // |differences| < 2^41 and |det| < 6 * 2^123: int128 holds it.
    const Vec3 a(p[0], p[1], p[2]), b(p[3], p[4], p[5]), c(p[6], p[7], p[8]), d(p[9], p[10], p[11]);
    ASSERT_EQ(exact_orient3d(a, b, c, d), sign_of_int128(int_orient3d(p)));
  }
}

TEST(Orient, SignConventions) {
  const Vec3 o(0, 0, 0), ex(1, 0, 0), ey(0, 1, 0), ez(0, 0, 1);
  EXPECT_EQ(orient3d(o, ex, ey, ez), 1);   // d on the side of (b-a)x(c-a)
  EXPECT_EQ(orient3d(o, ey, ex, ez), -1);
  EXPECT_EQ(orient3d(o, ex, ey, Vec3(0.3, 0.7, 0)), 0);
  EXPECT_EQ(orient2d(Vec2(0, 0), Vec2(1, 0), Vec2(0, 1)), 1);  // counterclockwise
  EXPECT_EQ(orient2d(Vec2(0, 0), Vec2(0, 1), Vec2(1, 0)), -1);
  EXPECT_EQ(orient2d(Vec2(0, 0), Vec2(1, 1), Vec2(3, 3)), 0);
  // Degenerate inputs: repeated points.
  EXPECT_EQ(orient3d(o, o, ey, ez), 0);
  EXPECT_EQ(orient3d(ex, ex, ex, ex), 0);
  EXPECT_EQ(orient2d(Vec2(1, 2), Vec2(1, 2), Vec2(5, 7)), 0);
  // orient2d_projected(axis) is the sign of component `axis` of (b-a) x (c-a).
  EXPECT_EQ(orient2d_projected(o, ex, ey, 2), 1);
  EXPECT_EQ(orient2d_projected(o, ey, ez, 0), 1);
  EXPECT_EQ(orient2d_projected(o, ez, ex, 1), 1);
}

TEST(Orient3d, SmallIntegerInputsAreExact) {
  // Coordinates in [-3, 3]: a large share of the cases is exactly coplanar.
  std::mt19937_64 rng(2);
  std::uniform_int_distribution<int> coord(-3, 3);
  int zeros = 0;
  for (int trial = 0; trial < 100000; ++trial) {
    std::array<std::int64_t, 12> p{};
    for (auto& x : p) x = coord(rng);
    const Vec3 a(p[0], p[1], p[2]), b(p[3], p[4], p[5]), c(p[6], p[7], p[8]), d(p[9], p[10], p[11]);
    const int expected = sign_of_int128(int_orient3d(p));
    ASSERT_EQ(orient3d(a, b, c, d), expected) << "trial " << trial;
    zeros += expected == 0;
  }
  EXPECT_GT(zeros, 1000);
}

TEST(Orient3d, OneUlpAroundAPlaneMatchesTwin) {
  // d is put on the plane (a, b, c) in double arithmetic, then moved by -3..3 ulps per
  // coordinate: the determinant is then tiny and plain double evaluation often gets its sign
  // wrong. Offsets up to 1e6 and mixed magnitudes are covered.
  std::mt19937_64 rng(3);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> step(-3, 3);
  const double offsets[] = {0.0, 1.0, 1e6, -3.7e4};
  const PredicateCounters before = predicate_counters();
  int naive_wrong = 0;
  int cases = 0;
  for (double offset : offsets) {
    for (int trial = 0; trial < 5000; ++trial) {
      const double size = std::ldexp(1.0, static_cast<int>(unit(rng) * 20) - 10);
      const Vec3 a = random_point(rng, size, offset);
      const Vec3 b = random_point(rng, size, offset);
      const Vec3 c = random_point(rng, size, offset);
      const double alpha = unit(rng) * 2 - 0.5;
      const double beta = unit(rng) * 2 - 0.5;
      Vec3 d = a + alpha * (b - a) + beta * (c - a);
      for (int k = 0; k < 3; ++k) d[k] = ulp_step(d[k], step(rng));
      const int expected = exact_orient3d(a, b, c, d);
      ASSERT_EQ(orient3d(a, b, c, d), expected) << "offset " << offset << " trial " << trial;
      // Permuting the arguments permutes the determinant's rows: exact signs must follow.
      ASSERT_EQ(orient3d(b, a, c, d), -expected);
      ASSERT_EQ(orient3d(b, c, a, d), expected);
      ASSERT_EQ(orient3d(a, b, d, c), -expected);
      ASSERT_EQ(orient3d(d, b, c, a), -expected);
      naive_wrong += naive_orient3d(a, b, c, d) != expected;
      ++cases;
    }
  }
  // The inputs are adversarial: plain double evaluation fails on a good share of them...
  const std::uint64_t fallbacks = predicate_counters().orient3d_exact - before.orient3d_exact;
  std::printf("[ info ] %d cases: plain double wrong on %d, exact fallback ran %llu times\n",
              cases, naive_wrong, static_cast<unsigned long long>(fallbacks));
  EXPECT_GT(naive_wrong, cases / 50) << naive_wrong << " of " << cases;
  // ...and the exact fallback did run.
  EXPECT_GT(fallbacks, static_cast<std::uint64_t>(cases));
}

TEST(Orient3d, ConstructedCoplanarPointsGiveZeroAndOneUlpOffGivesTheSide) {
  // a, b, c on a 2^-10 grid around an offset, d = a + alpha (b-a) + beta (c-a) with alpha,
  // beta multiples of 1/16: every value fits in 53 bits, so d is exactly on the plane.
  std::mt19937_64 rng(4);
  std::uniform_int_distribution<int> grid(-4096, 4096);
  std::uniform_int_distribution<int> frac(-32, 48);
  for (double offset : {0.0, 1e6, -2.5e5}) {
    for (int trial = 0; trial < 3000; ++trial) {
      auto grid_point = [&]() {
        return Vec3{offset + std::ldexp(grid(rng), -10), offset + std::ldexp(grid(rng), -10),
                    offset + std::ldexp(grid(rng), -10)};
      };
      const Vec3 a = grid_point(), b = grid_point(), c = grid_point();
      const double alpha = frac(rng) / 16.0;
      const double beta = frac(rng) / 16.0;
      const Vec3 d = a + alpha * (b - a) + beta * (c - a);
      ASSERT_EQ(exact_orient3d(a, b, c, d), 0);  // the construction is exact
      ASSERT_EQ(orient3d(a, b, c, d), 0);
      ASSERT_EQ(orient3d(d, c, a, b), 0);
      for (int k = 0; k < 3; ++k) {
        Vec3 moved = d;
        moved[k] = ulp_step(d[k], 1);
        ASSERT_EQ(orient3d(a, b, c, moved), exact_orient3d(a, b, c, moved));
        moved[k] = ulp_step(d[k], -1);
        ASSERT_EQ(orient3d(a, b, c, moved), exact_orient3d(a, b, c, moved));
      }
    }
  }
}

TEST(Orient3d, ExtremeMagnitudesWithinRange) {
  // Scaling by a power of two keeps the sign; exactness must hold near both ends of the
  // documented range and with mixed magnitudes inside one query.
  std::mt19937_64 rng(5);
  std::uniform_int_distribution<int> step(-2, 2);
  for (int scale_exp : {-190, -100, -30, 0, 30, 100, 190}) {
    const double s = std::ldexp(1.0, scale_exp);
    for (int trial = 0; trial < 500; ++trial) {
      const Vec3 a = random_point(rng, 1.0), b = random_point(rng, 1.0), c = random_point(rng, 1.0);
      Vec3 d = 0.25 * a + 0.5 * b + 0.25 * c;
      d[trial % 3] = ulp_step(d[trial % 3], step(rng));
      const int expected = exact_orient3d(a, b, c, d);
      ASSERT_EQ(orient3d(s * a, s * b, s * c, s * d), expected) << scale_exp;
      ASSERT_EQ(exact_orient3d(s * a, s * b, s * c, s * d), expected);
    }
  }
  // Mixed: a tiny triangle far from a huge point, and points differing in the last bit.
  const Vec3 a(1e-30, 0, 0), b(0, 1e-30, 0), c(0, 0, 1e-30);
  EXPECT_EQ(orient3d(a, b, c, Vec3(1e30, 1e30, 1e30)), exact_orient3d(a, b, c, Vec3(1e30, 1e30, 1e30)));
  const Vec3 p(1.0, 1.0, 1.0);
  const Vec3 q(std::nextafter(1.0, 2.0), 1.0, 1.0);
  const Vec3 r(1.0, std::nextafter(1.0, 2.0), 1.0);
  EXPECT_EQ(orient3d(p, q, r, Vec3(1.0, 1.0, std::nextafter(1.0, 2.0))), 1);
  EXPECT_EQ(orient3d(p, q, r, Vec3(1.0, 1.0, std::nextafter(1.0, 0.0))), -1);
}

TEST(Orient3d, FilterDecidesGenericInputs) {
  // Random points in general position must not need the exact fallback (the filter is what
  // makes the predicate cheap).
  std::mt19937_64 rng(6);
  const PredicateCounters before = predicate_counters();
  for (int trial = 0; trial < 10000; ++trial) {
    const Vec3 a = random_point(rng, 1.0), b = random_point(rng, 1.0), c = random_point(rng, 1.0),
               d = random_point(rng, 1.0);
    ASSERT_EQ(orient3d(a, b, c, d), naive_orient3d(a, b, c, d));
  }
  EXPECT_LE(predicate_counters().orient3d_exact - before.orient3d_exact, 5u);
}

TEST(Orient, SharedCoordinatesAreDecidedWithoutTheFallbackAndMatchTheTwin) {
  // Points on an axis-aligned plane (3D) or line (2D), as in a flat sheet of cloth: every
  // product of the filter's permanent is zero, which the predicates take as an exact zero.
  // Against the exact twin at both ends of the coordinate range, with zero coordinates mixed
  // in, and with the shared coordinate moved by an ulp (a nonzero sign the shortcut must not
  // take).
  std::mt19937_64 rng(11);
  std::uniform_int_distribution<int> pick(0, 2), step(-1, 1);
  int zeros = 0, nonzeros = 0, shortcut_zeros = 0;
  for (int scale_exp : {-190, -40, 0, 40, 190}) {
    const double s = std::ldexp(1.0, scale_exp);
    for (int trial = 0; trial < 2000; ++trial) {
      std::array<Vec3, 4> p;
      for (Vec3& q : p) q = s * random_point(rng, 1.0);
      const int axis = pick(rng);
      const double shared = trial % 5 == 0 ? 0.0 : p[0][axis];
      for (Vec3& q : p) q[axis] = shared;
      if (trial % 7 == 0) p[1][(axis + 1) % 3] = 0;  // a zero among the others
      const bool moved = trial % 2 == 1 && shared != 0;
      if (moved) p[3][axis] = ulp_step(shared, step(rng) == 0 ? 1 : -1);
      const PredicateCounters before = predicate_counters();
      const int got = orient3d(p[0], p[1], p[2], p[3]);
      const std::uint64_t fallbacks = predicate_counters().orient3d_exact - before.orient3d_exact;
      ASSERT_EQ(got, exact_orient3d(p[0], p[1], p[2], p[3])) << scale_exp << " trial " << trial;
      if (!moved) {
        EXPECT_EQ(fallbacks, 0u) << scale_exp << " trial " << trial;
        shortcut_zeros += got == 0;
      }
      (got == 0 ? zeros : nonzeros) += 1;
      // Three of the points in 2D (the shared coordinate and another one): on a line.
      const int other = (axis + 1) % 3;
      std::array<Vec2, 3> t;
      for (int k = 0; k < 3; ++k) t[static_cast<size_t>(k)] = Vec2(p[static_cast<size_t>(k)][axis], p[static_cast<size_t>(k)][other]);
      const PredicateCounters before2 = predicate_counters();
      const int got2 = orient2d(t[0], t[1], t[2]);
      ASSERT_EQ(got2, exact_orient2d(t[0], t[1], t[2])) << scale_exp << " trial " << trial;
      EXPECT_EQ(predicate_counters().orient2d_exact - before2.orient2d_exact, 0u);
    }
  }
  EXPECT_GT(shortcut_zeros, 1000);
  EXPECT_GT(nonzeros, 1000);
  EXPECT_GT(zeros, nonzeros / 2);
}

TEST(Orient2d, ClassroomNearCollinearGrid) {
  // Kettner et al., "Classroom examples of robustness problems in geometric computations":
  // p = (0.5 + i u, 0.5 + j u), u = 2^-53, against the line through (12, 12) and (24, 24).
  const Vec2 q(12, 12), r(24, 24);
  int naive_wrong = 0;
  for (int i = 0; i < 256; ++i) {
    for (int j = 0; j < 256; ++j) {
      const Vec2 p(0.5 + std::ldexp(i, -53), 0.5 + std::ldexp(j, -53));
      const int expected = exact_orient2d(p, q, r);
      ASSERT_EQ(orient2d(p, q, r), expected) << i << " " << j;
      ASSERT_EQ(orient2d(q, r, p), expected);
      ASSERT_EQ(orient2d(q, p, r), -expected);
      naive_wrong += naive_orient2d(p, q, r) != expected;
    }
  }
  EXPECT_GT(naive_wrong, 1000);
}

TEST(Orient2d, RandomNearCollinearMatchesTwin) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  std::uniform_int_distribution<int> step(-2, 2);
  for (double offset : {0.0, 1e6}) {
    for (int trial = 0; trial < 20000; ++trial) {
      const Vec2 a{offset + unit(rng), offset + unit(rng)};
      const Vec2 b{offset + unit(rng), offset + unit(rng)};
      const double t = unit(rng) * 3 - 1;
      Vec2 c = a + t * (b - a);
      c[0] = ulp_step(c[0], step(rng));
      c[1] = ulp_step(c[1], step(rng));
      const int expected = exact_orient2d(a, b, c);
      ASSERT_EQ(orient2d(a, b, c), expected);
      ASSERT_EQ(orient2d(b, a, c), -expected);
      ASSERT_EQ(orient2d(c, a, b), expected);
    }
  }
  // Small integers, many exactly collinear.
  std::uniform_int_distribution<int> coord(-3, 3);
  auto int_point = [&] {
    Vec2 p;
    for (int k = 0; k < 2; ++k) p[k] = coord(rng);
    return p;
  };
  for (int trial = 0; trial < 50000; ++trial) {
    const Vec2 a = int_point(), b = int_point(), c = int_point();
    const double det = (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]);  // exact
    ASSERT_EQ(orient2d(a, b, c), (det > 0) - (det < 0));
  }
}

TEST(Orient2dProjected, IsTheSignOfTheCrossProductComponent) {
  std::mt19937_64 rng(8);
  std::uniform_int_distribution<int> coord(-3, 3);
  auto int_point = [&] {
    Vec3 p;
    for (int k = 0; k < 3; ++k) p[k] = coord(rng);
    return p;
  };
  for (int trial = 0; trial < 20000; ++trial) {
    const Vec3 a = int_point(), b = int_point(), c = int_point();
    const Vec3 n = (b - a).cross(c - a);  // exact for small integers
    for (int axis = 0; axis < 3; ++axis) {
      ASSERT_EQ(orient2d_projected(a, b, c, axis), (n[axis] > 0) - (n[axis] < 0));
    }
  }
}

}  // namespace
}  // namespace vproxq
