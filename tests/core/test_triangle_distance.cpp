// Tests of point-triangle, segment-segment, triangle intersection and triangle-triangle distance
// against a brute-force twin.
//
// The twin: the distance between the convex hulls of two point sets P, Q (1..3 points each) is a
// convex QP in the barycentric coordinates. Its minimum is attained at a point whose active
// faces (a subset of P's points, a subset of Q's points) give a least-squares problem on the
// two affine hulls with a unique solution (take an extreme point of the optimal set), so it is
// found by enumerating all pairs of non-empty subsets (7 x 7 for two triangles), solving each
// unconstrained least-squares problem with a complete orthogonal decomposition (pseudo-inverse:
// degenerate hulls are fine) in long double, and keeping the feasible solutions (barycentric
// coordinates >= 0). It shares no code with the fast implementation and also finds intersections
// (distance ~0).
//
// Tolerances. The fast code works in double on coordinate differences; its result differs from
// the exact distance by a few roundings of quantities of the size of the coordinates, so the
// comparisons use kTolUlps * e * S, where e = 2^-53 and S is the largest coordinate magnitude
// of the query (1 when all are zero): 1.8e-15 for unit triangles at the origin, 1.8e-9 for unit
// triangles at 1e6. At 1e6 that is what double arithmetic can promise: a coordinate there is
// only resolved to ulp(1e6) = 1.2e-10 (relative error e = 1.1e-16 of 1e6), and every returned
// point is rounded to that grid. Distances themselves come out more accurately (they are
// computed from differences), which the printed worst cases show. The measured worst case of
// every comparison below is at most ~5 e*S (printed as "[ info ]" lines), so kTolUlps = 16
// leaves a margin of 3. The twin (long double, e = 2^-64, ~2000 times finer) counts as exact.
//
// Intersection: for triangles with small-integer corners the twin decides exactly (see the
// grid test); elsewhere the checks are that a pair the twin finds apart by more than the
// tolerance is not reported intersecting, that the exact decision is invariant under corner
// and argument order (an inexact test fails this near contact), and exact constructions.
#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <random>
#include <vector>

#include "core/geometry/point_triangle.hpp"
#include "core/geometry/predicates.hpp"
#include "core/geometry/segment_segment.hpp"
#include "core/geometry/separation_bound.hpp"
#include "core/geometry/triangle_distance.hpp"
#include "core/geometry/triangle_intersection.hpp"

namespace vproxq {
namespace {

using Real = long double;
using RVec = Eigen::Matrix<Real, 3, 1>;

/// Unit roundoff of double.
constexpr double kEpsilon = 0x1p-53;
/// Distances and point positions may be off by this many e * S (see the file comment).
constexpr double kTolUlps = 16.0;
/// Barycentric coordinates must be >= -kFeasibleTol in the twin. Zero on purpose: accepting a
/// slightly negative coordinate moves the point out of its hull and lowers the distance to
/// first order, while rejecting a solution whose coordinate is negative only by long double
/// noise costs nothing measurable: the optimum then lies within that noise of a smaller face
/// pair, also enumerated, where the distance differs only to second order.
constexpr Real kFeasibleTol = 0.0L;

struct TwinResult {
  Real distance = std::numeric_limits<Real>::infinity();
  RVec point_p = RVec::Zero();
  RVec point_q = RVec::Zero();
};

/// Distance between the convex hulls of p and q (1 to 3 points each), by face-pair enumeration.
TwinResult twin_hull_distance(const std::vector<Vec3>& p, const std::vector<Vec3>& q) {
  TwinResult best;
  const int np = static_cast<int>(p.size());
  const int nq = static_cast<int>(q.size());
  for (int mp = 1; mp < (1 << np); ++mp) {
    for (int mq = 1; mq < (1 << nq); ++mq) {
      std::vector<int> ip, iq;
      for (int i = 0; i < np; ++i) if (mp & (1 << i)) ip.push_back(i);
      for (int j = 0; j < nq; ++j) if (mq & (1 << j)) iq.push_back(j);
      const RVec p0 = p[ip[0]].cast<Real>();
      const RVec q0 = q[iq[0]].cast<Real>();
      const int cols = static_cast<int>(ip.size() + iq.size()) - 2;
      // x - y = (p0 - q0) + sum_i alpha_i (p_i - p0) - sum_j beta_j (q_j - q0)
      Eigen::Matrix<Real, 3, Eigen::Dynamic> m(3, cols);
      int c = 0;
      for (std::size_t i = 1; i < ip.size(); ++i) m.col(c++) = p[ip[i]].cast<Real>() - p0;
      for (std::size_t j = 1; j < iq.size(); ++j) m.col(c++) = -(q[iq[j]].cast<Real>() - q0);
      const RVec base = p0 - q0;
      Eigen::Matrix<Real, Eigen::Dynamic, 1> z = Eigen::Matrix<Real, Eigen::Dynamic, 1>::Zero(cols);
      if (cols > 0) {
        z = m.completeOrthogonalDecomposition().solve(-base);
      }
      // Barycentric coordinates of both points.
      Real sum_alpha = 0, sum_beta = 0;
      bool feasible = true;
      for (std::size_t i = 1; i < ip.size(); ++i) {
        feasible &= z(static_cast<int>(i - 1)) >= -kFeasibleTol;
        sum_alpha += z(static_cast<int>(i - 1));
      }
      for (std::size_t j = 1; j < iq.size(); ++j) {
        const Real beta = z(static_cast<int>(ip.size() - 1 + j - 1));
        feasible &= beta >= -kFeasibleTol;
        sum_beta += beta;
      }
      feasible &= 1 - sum_alpha >= -kFeasibleTol && 1 - sum_beta >= -kFeasibleTol;
      if (!feasible) continue;
      const RVec diff = base + m * z;
      const Real d = diff.norm();
      if (d < best.distance) {
        best.distance = d;
        RVec x = p0;
        for (std::size_t i = 1; i < ip.size(); ++i) x += z(static_cast<int>(i - 1)) * m.col(static_cast<int>(i - 1));
        best.point_p = x;
        best.point_q = x - diff;
      }
    }
  }
  return best;
}

std::vector<Vec3> as_points(const Triangle& t) { return {t[0], t[1], t[2]}; }

Real twin_point_triangle(const Vec3& x, const Triangle& t) {
  return twin_hull_distance({x}, as_points(t)).distance;
}

/// S of the file comment: largest coordinate magnitude or extent (1 for all-zero input).
double scale_of(const std::vector<Vec3>& points) {
  double s = 0.0;
  for (const Vec3& x : points) s = std::max(s, x.cwiseAbs().maxCoeff());
  return s > 0.0 ? s : 1.0;
}
double scale_of(const Triangle& a, const Triangle& b) {
  return scale_of({a[0], a[1], a[2], b[0], b[1], b[2]});
}

/// Worst errors seen, in units of e * S, printed by the random tests.
struct ErrorStats {
  double distance = 0;
  double points = 0;
  double intersection_point = 0;
  int intersecting = 0;
  int cases = 0;
  void print(const char* name) const {
    std::printf("[ info ] %s: %d cases, %d intersecting; worst error / (e*S): distance %.2f, "
                "points on triangles %.2f, intersection point %.2f\n",
                name, cases, intersecting, distance, points, intersection_point);
  }
};

/// Index of the first minimum of the 15 feature-pair candidates, recomputed from the public
/// primitives (0..2 VF, 3..5 FV, 6..14 EE row-major).
int first_minimum_candidate(const Triangle& a, const Triangle& b) {
  double best = kInfinity;
  int best_index = -1;
  auto consider = [&](double sq, int index) {
    if (sq < best) {
      best = sq;
      best_index = index;
    }
  };
  for (int i = 0; i < 3; ++i) consider(point_triangle_distance(a[i], b).squared_distance, i);
  for (int j = 0; j < 3; ++j) consider(point_triangle_distance(b[j], a).squared_distance, 3 + j);
  for (int ea = 0; ea < 3; ++ea) {
    for (int eb = 0; eb < 3; ++eb) {
      consider(segment_segment_distance(a[ea], a[(ea + 1) % 3], b[eb], b[(eb + 1) % 3]).squared_distance,
               6 + 3 * ea + eb);
    }
  }
  return best_index;
}

/// The distance triangle_distance() reports for a winning candidate's squared distance: its
/// square root, but the smallest positive double for 0 (0 is for touching triangles alone).
double reported_distance(double squared) {
  const double d = std::sqrt(squared);
  return d == 0.0 ? std::numeric_limits<double>::denorm_min() : d;
}

/// r and s are bitwise the same result.
void expect_bitwise_equal(const TriangleDistanceResult& r, const TriangleDistanceResult& s, const char* what) {
  EXPECT_EQ(std::memcmp(&r.distance, &s.distance, sizeof r.distance), 0)
      << what << ": distance " << r.distance << " against " << s.distance;
  EXPECT_EQ(std::memcmp(r.point_a.data(), s.point_a.data(), 3 * sizeof(double)), 0) << what;
  EXPECT_EQ(std::memcmp(r.point_b.data(), s.point_b.data(), 3 * sizeof(double)), 0) << what;
  EXPECT_EQ(r.kind, s.kind) << what;
  EXPECT_EQ(r.feature_a, s.feature_a) << what;
  EXPECT_EQ(r.feature_b, s.feature_b) << what;
}

/// triangle_distance's pruning skips only candidates that cannot win: r is bitwise the result
/// of the search over all 15 candidates. So is the two-step search (distance first, points
/// after), with the triangles prepared by the caller (from PreparedTriangleParts) or not, and
/// with a caller's bound or none.
void expect_same_as_unpruned(const Triangle& a, const Triangle& b, const TriangleDistanceResult& r) {
  const TriangleDistanceResult all = detail::triangle_distance_unpruned(a, b);
  expect_bitwise_equal(r, all, "pruned");
  const PreparedTriangle pa = prepared_from_parts(a, parts_of(prepare_triangle(a)));
  const PreparedTriangle pb = prepared_from_parts(b, parts_of(prepare_triangle(b)));
  for (const bool prepared : {false, true}) {
    // With a caller's bound (infinity: none): the same numbers exactly when the distance is
    // within it, around the distance and far from it; the distance before the points too.
    const double d = all.distance;
    for (const double within : {0.0, d * 0.5, std::nextafter(d, 0.0), d, std::nextafter(d, kInfinity), d * 2,
                                d * 1e6 + 1, kInfinity}) {
      TriangleDistanceResult w;
      const bool kept = triangle_distance_within(a, prepared ? &pa : nullptr, b, prepared ? &pb : nullptr, within, w);
      EXPECT_EQ(kept, d <= within) << "within " << within << ", distance " << d;
      if (!kept) continue;
      EXPECT_EQ(std::memcmp(&w.distance, &all.distance, sizeof w.distance), 0) << "before the points";
      add_closest_points(w, a, prepared ? &pa : nullptr, b, prepared ? &pb : nullptr);
      expect_bitwise_equal(w, all, prepared ? "two steps, prepared" : "two steps");
    }
  }
}

/// All checks of one triangle pair against the twin; returns the result.
TriangleDistanceResult check_pair(const Triangle& a, const Triangle& b, ErrorStats* stats = nullptr) {
  const double unit = kEpsilon * scale_of(a, b);
  const double tol = kTolUlps * unit;
  const TriangleDistanceResult r = triangle_distance(a, b);
  expect_same_as_unpruned(a, b, r);
  const TwinResult twin = twin_hull_distance(as_points(a), as_points(b));
  const bool intersect = triangles_intersect(a, b);
  const auto d_twin = static_cast<double>(twin.distance);

  EXPECT_NEAR(r.distance, d_twin, tol);
  EXPECT_EQ(intersect, r.kind == TriangleDistanceCase::Intersecting);
  EXPECT_EQ(intersect, triangles_intersect(b, a));
  if (d_twin > tol) {
    EXPECT_FALSE(intersect) << "twin distance " << d_twin;
  }
  const double pa_err = static_cast<double>(twin_point_triangle(r.point_a, a));
  const double pb_err = static_cast<double>(twin_point_triangle(r.point_b, b));
  if (intersect) {
    EXPECT_EQ(r.distance, 0.0);
    EXPECT_EQ(r.point_a, r.point_b);
    EXPECT_EQ(r.feature_a, -1);
    EXPECT_EQ(r.feature_b, -1);
    EXPECT_LE(pa_err, tol);
    EXPECT_LE(pb_err, tol);
  } else {
    EXPECT_LE(pa_err, tol);
    EXPECT_LE(pb_err, tol);
    EXPECT_NEAR((r.point_a - r.point_b).norm(), r.distance, tol);
    EXPECT_GT(r.distance, 0.0);
    // The reported feature pair is the first minimum in the documented order, and its
    // distance and points are bitwise those of the stand-alone primitive.
    const int first = first_minimum_candidate(a, b);
    if (first < 3) {
      EXPECT_EQ(r.kind, TriangleDistanceCase::VertexFace);
      EXPECT_EQ(r.feature_a, first);
      EXPECT_EQ(r.feature_b, -1);
      const PointTriangleResult p = point_triangle_distance(a[first], b);
      EXPECT_EQ(r.distance, reported_distance(p.squared_distance));
      EXPECT_EQ(r.point_a, a[first]);
      EXPECT_EQ(r.point_b, p.closest);
    } else if (first < 6) {
      EXPECT_EQ(r.kind, TriangleDistanceCase::FaceVertex);
      EXPECT_EQ(r.feature_a, -1);
      EXPECT_EQ(r.feature_b, first - 3);
      const PointTriangleResult p = point_triangle_distance(b[first - 3], a);
      EXPECT_EQ(r.distance, reported_distance(p.squared_distance));
      EXPECT_EQ(r.point_a, p.closest);
      EXPECT_EQ(r.point_b, b[first - 3]);
    } else {
      const int ea = (first - 6) / 3;
      const int eb = (first - 6) % 3;
      EXPECT_EQ(r.kind, TriangleDistanceCase::EdgeEdge);
      EXPECT_EQ(r.feature_a, ea);
      EXPECT_EQ(r.feature_b, eb);
      const SegmentSegmentResult e = segment_segment_distance(a[ea], a[(ea + 1) % 3], b[eb], b[(eb + 1) % 3]);
      EXPECT_EQ(r.distance, reported_distance(e.squared_distance));
      EXPECT_EQ(r.point_a, e.point_a);
      EXPECT_EQ(r.point_b, e.point_b);
    }
  }
  if (stats != nullptr) {
    ++stats->cases;
    stats->distance = std::max(stats->distance, std::fabs(r.distance - d_twin) / unit);
    if (intersect) {
      ++stats->intersecting;
      stats->intersection_point = std::max(stats->intersection_point, std::max(pa_err, pb_err) / unit);
    } else {
      stats->points = std::max(stats->points, std::max(pa_err, pb_err) / unit);
    }
  }
  return r;
}

Vec3 random_vec(std::mt19937_64& rng, double half_size) {
  std::uniform_real_distribution<double> u(-half_size, half_size);
  return Vec3{u(rng), u(rng), u(rng)};
}

Triangle random_triangle(std::mt19937_64& rng, const Vec3& center, double half_size) {
  return {center + random_vec(rng, half_size), center + random_vec(rng, half_size),
          center + random_vec(rng, half_size)};
}


/// The 6 orderings of a triangle's corners.
std::array<Triangle, 6> corner_orders(const Triangle& t) {
  return {{{t[0], t[1], t[2]}, {t[1], t[2], t[0]}, {t[2], t[0], t[1]},
           {t[0], t[2], t[1]}, {t[2], t[1], t[0]}, {t[1], t[0], t[2]}}};
}

/// Exact decisions do not depend on corner order or argument order: 72 evaluations agree.
void expect_order_invariant_intersection(const Triangle& a, const Triangle& b, bool expected) {
  for (const Triangle& pa : corner_orders(a)) {
    for (const Triangle& pb : corner_orders(b)) {
      ASSERT_EQ(triangles_intersect(pa, pb), expected);
      ASSERT_EQ(triangles_intersect(pb, pa), expected);
    }
  }
}

// ---- point-triangle and segment-segment ---------------------------------------------------

TEST(PointTriangle, MatchesTwinOnRandomAndDegenerateTriangles) {
  std::mt19937_64 rng(11);
  double worst = 0;
  for (double offset : {0.0, 1e6}) {
    const Vec3 shift = Vec3::Constant(offset);
    for (int trial = 0; trial < 6000; ++trial) {
      Triangle t = random_triangle(rng, shift, 1.0);
      switch (trial % 6) {
        case 1: t[2] = t[0] + 0.5 * (t[1] - t[0]); break;            // collinear (nearly exact)
        case 2: t[1] = t[0]; break;                                   // repeated corner
        case 3: t[1] = t[0]; t[2] = t[0]; break;                      // a point
        case 4: t[2] = t[0] + (1 + 1e-9) * (t[1] - t[0]); break;      // cap sliver
        case 5: t[2] = t[1] + 1e-7 * random_vec(rng, 1.0); break;    // needle
        default: break;
      }
      const Vec3 p = shift + random_vec(rng, 2.0);
      const PointTriangleResult r = point_triangle_distance(p, t);
      const double unit = kEpsilon * scale_of({t[0], t[1], t[2], p});
      const double d_twin = static_cast<double>(twin_point_triangle(p, t));
      ASSERT_NEAR(std::sqrt(r.squared_distance), d_twin, kTolUlps * unit) << "trial " << trial;
      ASSERT_LE(static_cast<double>(twin_point_triangle(r.closest, t)), kTolUlps * unit);
      ASSERT_NEAR((r.closest - p).norm(), std::sqrt(r.squared_distance), kTolUlps * unit);
      worst = std::max(worst, std::fabs(std::sqrt(r.squared_distance) - d_twin) / unit);
      // The prepared overload is the same computation, bitwise.
      const PointTriangleResult again = point_triangle_distance(p, prepare_triangle(t));
      ASSERT_EQ(again.squared_distance, r.squared_distance);
      ASSERT_EQ(again.closest, r.closest);
      ASSERT_EQ(again.region, r.region);
    }
  }
  std::printf("[ info ] point-triangle worst distance error %.2f e*S\n", worst);
}

TEST(PointTriangle, CapSliversMatchTwin) {
  // Caps: the third corner within 1e-4 .. 1e-18 of the segment between the other two, queried
  // from points close to the sliver (where the plane's direction matters most). A normal
  // computed in plain double is off by ~e/sin radians here; the accurate normal keeps the
  // error at a few e*S.
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> unit01(0.0, 1.0);
  double worst = 0;
  int face = 0;
  for (double offset : {0.0, 1e6}) {
    const Vec3 shift = Vec3::Constant(offset);
    for (int trial = 0; trial < 20000; ++trial) {
      const Vec3 a = shift + random_vec(rng, 1.0);
      const Vec3 b = shift + random_vec(rng, 1.0);
      const double height = std::pow(10.0, -4.0 - 14.0 * unit01(rng));
      const double along_c = unit01(rng);
      const Vec3 c = a + along_c * (b - a) + height * random_vec(rng, 1.0);
      const Triangle t = {a, b, c};
      const double along_p = unit01(rng);
      const double offset_p = std::pow(10.0, -6.0 * unit01(rng));
      const Vec3 p = a + along_p * (b - a) + offset_p * random_vec(rng, 1.0);
      const PointTriangleResult r = point_triangle_distance(p, t);
      const double unit = kEpsilon * scale_of({a, b, c, p});
      const double d_twin = static_cast<double>(twin_point_triangle(p, t));
      ASSERT_NEAR(std::sqrt(r.squared_distance), d_twin, kTolUlps * unit) << "trial " << trial;
      ASSERT_LE(static_cast<double>(twin_point_triangle(r.closest, t)), kTolUlps * unit);
      worst = std::max(worst, std::fabs(std::sqrt(r.squared_distance) - d_twin) / unit);
      face += r.region == PointTriangleRegion::Face;
    }
  }
  std::printf("[ info ] cap slivers: worst distance error %.2f e*S, %d Face results\n", worst, face);
  EXPECT_GT(face, 200);  // the face path of caps is exercised
}

TEST(PointTriangle, NeedlesMatchTheirKnownDistance) {
  // Needles: a short edge 1e-2 .. 1e-14 long beside two edges about 2 long, in the plane
  // z = offset, queried from a point of the needle raised by h (1 .. 1e-8, either side), so
  // the distance is |h| up to the rounding of the point's in-plane coordinates (a few e*S).
  // Their largest angle is not small, but barycentric coordinates along the needle lose about
  // (long edge / short edge) e of accuracy: built from them, a point 1e-14 wide needle's
  // distance came out off by up to about 1 (found by tests/fuzz/fuzz_ccd_kernel.cpp).
  // triangle_distance() against the point as a triangle must agree.
  std::mt19937_64 rng(14);
  std::uniform_real_distribution<double> unit01(0.0, 1.0), sym(-1.0, 1.0);
  double worst = 0;
  int face = 0;
  for (double offset : {0.0, 1e6}) {
    for (int trial = 0; trial < 20000; ++trial) {
      const double short_edge = std::pow(10.0, -2.0 - 12.0 * unit01(rng));
      double xy[6];
      for (double& x : xy) x = sym(rng);
      const Vec3 a(offset + xy[0], offset + xy[1], offset);
      const Vec3 b = a + Vec3(2 * xy[2], 2 * xy[3], 0);
      const Vec3 c = b + Vec3(short_edge * xy[4], short_edge * xy[5], 0);
      const Triangle t = {a, b, c};
      const double w1 = unit01(rng);
      const double w2 = unit01(rng) * (1 - w1);
      const double h = std::pow(10.0, -8.0 * unit01(rng)) * (unit01(rng) < 0.5 ? -1 : 1);
      Vec3 p = a + w1 * (b - a) + w2 * (c - a);
      p.z() = offset + h;
      const double expected = std::fabs(p.z() - offset);  // exact (Sterbenz)
      const double unit = kEpsilon * scale_of({a, b, c, p});
      const PointTriangleResult r = point_triangle_distance(p, t);
      ASSERT_NEAR(std::sqrt(r.squared_distance), expected, kTolUlps * unit)
          << "offset " << offset << " trial " << trial << " short edge " << short_edge;
      ASSERT_NEAR(triangle_distance(t, Triangle{p, p, p}).distance, expected, kTolUlps * unit)
          << "offset " << offset << " trial " << trial << " short edge " << short_edge;
      worst = std::max(worst, std::fabs(std::sqrt(r.squared_distance) - expected) / unit);
      face += r.region == PointTriangleRegion::Face;
    }
  }
  std::printf("[ info ] needles: worst distance error %.2f e*S, %d Face results\n", worst, face);
  EXPECT_GT(face, 20000);  // most points project into the needle
}

TEST(PointTriangle, Regions) {
  const Triangle t = {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0)};
  auto region = [&](const Vec3& p) { return point_triangle_distance(p, t).region; };
  EXPECT_EQ(region(Vec3(1, 1, 3)), PointTriangleRegion::Face);
  EXPECT_EQ(region(Vec3(-1, -1, 1)), PointTriangleRegion::Vertex0);
  EXPECT_EQ(region(Vec3(5, -1, 0)), PointTriangleRegion::Vertex1);
  EXPECT_EQ(region(Vec3(-1, 5, 2)), PointTriangleRegion::Vertex2);
  EXPECT_EQ(region(Vec3(2, -1, 1)), PointTriangleRegion::Edge0);
  EXPECT_EQ(region(Vec3(3, 3, 1)), PointTriangleRegion::Edge1);
  EXPECT_EQ(region(Vec3(-1, 2, -1)), PointTriangleRegion::Edge2);
  const PointTriangleResult face = point_triangle_distance(Vec3(1, 1, 3), t);
  EXPECT_EQ(face.squared_distance, 9.0);
  EXPECT_EQ(face.closest, Vec3(1, 1, 0));
  // Degenerate triangles never report Face; a point triangle reports Vertex0.
  const Triangle line = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(4, 0, 0)};
  const PointTriangleResult on_line = point_triangle_distance(Vec3(3, 1, 0), line);
  EXPECT_EQ(on_line.squared_distance, 1.0);
  EXPECT_EQ(on_line.region, PointTriangleRegion::Edge1);
  const Triangle point = {Vec3(1, 2, 3), Vec3(1, 2, 3), Vec3(1, 2, 3)};
  const PointTriangleResult to_point = point_triangle_distance(Vec3(1, 2, 5), point);
  EXPECT_EQ(to_point.squared_distance, 4.0);
  EXPECT_EQ(to_point.region, PointTriangleRegion::Vertex0);
}

TEST(SegmentSegment, MatchesTwinIncludingParallelAndDegenerate) {
  std::mt19937_64 rng(12);
  std::uniform_real_distribution<double> unit01(0.0, 1.0);
  double worst = 0;
  for (double offset : {0.0, 1e6}) {
    const Vec3 shift = Vec3::Constant(offset);
    for (int trial = 0; trial < 8000; ++trial) {
      const Vec3 p0 = shift + random_vec(rng, 1.0);
      Vec3 p1 = shift + random_vec(rng, 1.0);
      Vec3 q0 = shift + random_vec(rng, 1.0);
      Vec3 q1 = shift + random_vec(rng, 1.0);
      const Vec3 dir = p1 - p0;
      const double gap = std::pow(10.0, -12.0 * unit01(rng));
      switch (trial % 8) {
        case 1: q1 = q0 + 0.7 * dir; break;                                       // parallel
        case 2: q1 = q0 + dir + 1e-9 * random_vec(rng, 1.0); break;              // nearly
        case 3: q1 = q0 + dir + 1e-15 * random_vec(rng, 1.0); break;             // very nearly
        case 4: q0 = p0 + 0.3 * dir + gap * random_vec(rng, 1.0);                 // nearly
                q1 = q0 + 0.9 * dir + 1e-12 * random_vec(rng, 1.0); break;       // touching
        case 5: p1 = p0; break;                                                   // a point
        case 6: p1 = p0; q1 = q0; break;                                          // two points
        case 7: q0 = p0 + 0.5 * dir + gap * random_vec(rng, 1.0); break;          // near cross
        default: break;
      }
      const SegmentSegmentResult r = segment_segment_distance(p0, p1, q0, q1);
      const double u = kEpsilon * scale_of({p0, p1, q0, q1});
      const double d_twin = static_cast<double>(twin_hull_distance({p0, p1}, {q0, q1}).distance);
      const double d = std::sqrt(r.squared_distance);
      ASSERT_NEAR(d, d_twin, kTolUlps * u) << "trial " << trial;
      ASSERT_LE(static_cast<double>(twin_hull_distance({r.point_a}, {p0, p1}).distance), kTolUlps * u);
      ASSERT_LE(static_cast<double>(twin_hull_distance({r.point_b}, {q0, q1}).distance), kTolUlps * u);
      ASSERT_NEAR((r.point_a - r.point_b).norm(), d, kTolUlps * u);
      ASSERT_TRUE(r.s >= 0.0 && r.s <= 1.0 && r.t >= 0.0 && r.t <= 1.0);
      worst = std::max(worst, std::fabs(d - d_twin) / u);
    }
  }
  std::printf("[ info ] segment-segment worst distance error %.2f e*S\n", worst);
}

TEST(SegmentSegment, ExactSmallCases) {
  // Crossing skew segments, distance 1 at the interior.
  SegmentSegmentResult r = segment_segment_distance(Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, -1, 1), Vec3(0, 1, 1));
  EXPECT_EQ(r.squared_distance, 1.0);
  EXPECT_EQ(r.kind, SegmentSegmentCase::Interior);
  EXPECT_EQ(r.point_a, Vec3(0, 0, 0));
  EXPECT_EQ(r.point_b, Vec3(0, 0, 1));
  // Parallel overlapping: distance 2, from the boundary.
  r = segment_segment_distance(Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(1, 2, 0), Vec3(6, 2, 0));
  EXPECT_EQ(r.squared_distance, 4.0);
  EXPECT_NE(r.kind, SegmentSegmentCase::Interior);
  // Collinear, disjoint: endpoint to endpoint.
  r = segment_segment_distance(Vec3(0, 0, 0), Vec3(1, 1, 1), Vec3(3, 3, 3), Vec3(2, 2, 2));
  EXPECT_EQ(r.squared_distance, 3.0);
  EXPECT_EQ(r.point_a, Vec3(1, 1, 1));
  EXPECT_EQ(r.point_b, Vec3(2, 2, 2));
  // Point against segment and point against point.
  r = segment_segment_distance(Vec3(1, 5, 0), Vec3(1, 5, 0), Vec3(0, 0, 0), Vec3(2, 0, 0));
  EXPECT_EQ(r.squared_distance, 25.0);
  EXPECT_EQ(r.point_b, Vec3(1, 0, 0));
  r = segment_segment_distance(Vec3(1, 1, 1), Vec3(1, 1, 1), Vec3(1, 1, 1), Vec3(1, 1, 1));
  EXPECT_EQ(r.squared_distance, 0.0);
}

// ---- exact intersection ----------------------------------------------------------------------

TEST(TriangleIntersection, SmallIntegerTrianglesAgreeExactlyWithTwin) {
  // Corners on the grid {0..3}^3: many coplanar, collinear, repeated-corner and touching cases.
  // A nonzero distance between such triangles is at least 1/sqrt(27^3) ~ 7e-3 (squared distance
  // is a ratio of integer Gram determinants with denominator <= 27^3), so the twin decides
  // intersection unambiguously with the threshold below.
  constexpr double kGridContactThreshold = 1e-9;
  std::mt19937_64 rng(21);
  std::uniform_int_distribution<int> coord(0, 3);
  auto grid_triangle = [&]() {
    Triangle t;
    for (Vec3& c : t)
      for (int k = 0; k < 3; ++k) c[k] = coord(rng);
    return t;
  };
  int intersecting = 0, degenerate = 0, coplanar = 0;
  for (int trial = 0; trial < 30000; ++trial) {
    const Triangle a = grid_triangle();
    const Triangle b = grid_triangle();
    const Real d_twin = twin_hull_distance(as_points(a), as_points(b)).distance;
    const bool expected = d_twin < kGridContactThreshold;
    ASSERT_EQ(triangles_intersect(a, b), expected) << "trial " << trial;
    ASSERT_EQ(triangles_intersect(b, a), expected) << "trial " << trial;
    intersecting += expected;
    degenerate += triangle_is_degenerate(a) || triangle_is_degenerate(b);
    coplanar += orient3d(a[0], a[1], a[2], b[0]) == 0 && orient3d(a[0], a[1], a[2], b[1]) == 0 &&
                orient3d(a[0], a[1], a[2], b[2]) == 0;
    if (trial < 3000) {
      check_pair(a, b);
    }
  }
  std::printf("[ info ] grid: 30000 pairs, %d intersecting, %d with a degenerate triangle, %d "
              "coplanar\n", intersecting, degenerate, coplanar);
  EXPECT_GT(intersecting, 3000);
  EXPECT_GT(degenerate, 1000);
  EXPECT_GT(coplanar, 300);
}

TEST(TriangleIntersection, NearContactDecisionsAreOrderInvariant) {
  // Corners placed on or next to the other triangle in double arithmetic (so the exact answer
  // is a coin flip decided by the last bits): the exact decision must not depend on the order
  // of corners or arguments, and must agree with the twin when the twin is clear.
  std::mt19937_64 rng(22);
  std::uniform_real_distribution<double> unit01(0.0, 1.0);
  int intersecting = 0;
  for (double offset : {0.0, 1e6}) {
    const Vec3 shift = Vec3::Constant(offset);
    for (int trial = 0; trial < 1500; ++trial) {
      const Triangle a = random_triangle(rng, shift, 1.0);
      double u = unit01(rng), v = unit01(rng);
      if (u + v > 1) { u = 1 - u; v = 1 - v; }
      const Vec3 on_face = a[0] + u * (a[1] - a[0]) + v * (a[2] - a[0]);
      const Vec3 on_edge = a[0] + u * (a[1] - a[0]);
      Triangle b;
      switch (trial % 4) {
        case 0:  // vertex on the face
          b = {on_face, on_face + random_vec(rng, 1.0), on_face + random_vec(rng, 1.0)};
          break;
        case 1: {  // edge through an edge
          const Vec3 dir = random_vec(rng, 1.0);
          b = {on_edge - dir, on_edge + dir, on_edge + random_vec(rng, 1.0)};
          break;
        }
        case 2: {  // nearly coplanar, overlapping the boundary
          const Vec3 n = (a[1] - a[0]).cross(a[2] - a[0]);
          b = {on_edge, on_edge + (a[2] - a[1]) * unit01(rng) + 1e-17 * n, on_face + (a[1] - a[0])};
          break;
        }
        default:  // vertex on an edge
          b = {on_edge, on_edge + random_vec(rng, 1.0), on_edge + random_vec(rng, 1.0)};
          break;
      }
      const bool expected = triangles_intersect(a, b);
      intersecting += expected;
      expect_order_invariant_intersection(a, b, expected);
      check_pair(a, b);
    }
  }
  std::printf("[ info ] near contact: 3000 pairs, %d intersecting\n", intersecting);
}

TEST(TriangleIntersection, ConstructedTouchingCases) {
  // Exact constructions (dyadic coordinates): touching counts, and a gap of 2^-30 does not.
  const double g = std::ldexp(1.0, -30);
  const Triangle a = {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(0, 4, 0)};
  struct Case {
    const char* name;
    Triangle b;
    bool intersecting;
  };
  const std::vector<Case> cases = {
      // Coplanar (z = 0).
      {"coplanar overlap", {Vec3(1, 1, 0), Vec3(5, 1, 0), Vec3(1, 5, 0)}, true},
      {"coplanar inside", {Vec3(1, 1, 0), Vec3(2, 1, 0), Vec3(1, 2, 0)}, true},
      {"coplanar containing", {Vec3(-1, -1, 0), Vec3(9, -1, 0), Vec3(-1, 9, 0)}, true},
      {"coplanar shared vertex", {Vec3(4, 0, 0), Vec3(6, -1, 0), Vec3(6, 1, 0)}, true},
      {"coplanar vertex on edge", {Vec3(2, 0, 0), Vec3(3, -2, 0), Vec3(1, -2, 0)}, true},
      {"coplanar shared edge", {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(2, -3, 0)}, true},
      {"coplanar edge overlap", {Vec3(1, 0, 0), Vec3(6, 0, 0), Vec3(3, -3, 0)}, true},
      {"coplanar crossing edges", {Vec3(3, -1, 0), Vec3(3, 3, 0), Vec3(7, 1, 0)}, true},
      {"coplanar gap at vertex", {Vec3(4 + g, 0, 0), Vec3(6, -1, 0), Vec3(6, 1, 0)}, false},
      {"coplanar gap at edge", {Vec3(2, -g, 0), Vec3(3, -2, 0), Vec3(1, -2, 0)}, false},
      {"coplanar gap at hypotenuse", {Vec3(2 + g, 2 + g, 0), Vec3(5, 5, 0), Vec3(3, 6, 0)}, false},
      // 3D.
      {"vertex on face", {Vec3(1, 1, 0), Vec3(1, 2, 3), Vec3(2, 1, 3)}, true},
      {"vertex above face", {Vec3(1, 1, g), Vec3(1, 2, 3), Vec3(2, 1, 3)}, false},
      {"vertex on edge", {Vec3(2, 0, 0), Vec3(2, -1, 3), Vec3(3, -1, 2)}, true},
      {"vertex on vertex", {Vec3(0, 4, 0), Vec3(1, 5, 1), Vec3(-1, 5, 2)}, true},
      {"edge on face", {Vec3(1, 1, 0), Vec3(2, 1, 0), Vec3(1, 1, 5)}, true},
      {"shared edge, folded", {Vec3(0, 0, 0), Vec3(4, 0, 0), Vec3(2, -1, 3)}, true},
      {"edge through face", {Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(5, 5, 3)}, true},
      {"edge through edge", {Vec3(2, -1, 1), Vec3(2, 1, -1), Vec3(2, -3, -1)}, true},
      {"edge past edge", {Vec3(2, -1 - g, 1), Vec3(2, 1 - g, -1), Vec3(2, -3, -1)}, false},
      {"piercing, no corner inside", {Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(-3, -3, 0)}, true},
      // Degenerate b.
      {"segment crossing face", {Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(1, 1, 3)}, true},
      {"segment above face", {Vec3(1, 1, g), Vec3(1, 1, 1), Vec3(1, 1, 3)}, false},
      {"segment in plane across", {Vec3(-1, 1, 0), Vec3(1, 1, 0), Vec3(5, 1, 0)}, true},
      {"segment in plane outside", {Vec3(-1, -1, 0), Vec3(-2, -2, 0), Vec3(-3, -3, 0)}, false},
      {"segment touching vertex", {Vec3(-2, 8, 0), Vec3(0, 4, 0), Vec3(-1, 6, 0)}, true},
      {"point on face", {Vec3(1, 1, 0), Vec3(1, 1, 0), Vec3(1, 1, 0)}, true},
      {"point on edge", {Vec3(0, 3, 0), Vec3(0, 3, 0), Vec3(0, 3, 0)}, true},
      {"point off face", {Vec3(1, 1, g), Vec3(1, 1, g), Vec3(1, 1, g)}, false},
      {"point in plane outside", {Vec3(3, 3, 0), Vec3(3, 3, 0), Vec3(3, 3, 0)}, false},
  };
  // Integer maps that tilt the whole configuration (exact for these small dyadic numbers;
  // affine maps preserve incidence, so the expected answers stay the same).
  const std::vector<Eigen::Matrix3d> maps = {
      Eigen::Matrix3d::Identity(),
      (Eigen::Matrix3d() << 1, 2, 0, 0, 1, 3, 1, 0, 1).finished(),
      (Eigen::Matrix3d() << 0, 1, 1, 1, 0, 1, 1, 1, 0).finished(),
  };
  for (const Eigen::Matrix3d& m : maps) {
    for (const Vec3& shift : {Vec3(0, 0, 0), Vec3(1e6, -1e6, 1e6)}) {
      auto map = [&](const Triangle& t) {
        return Triangle{m * t[0] + shift, m * t[1] + shift, m * t[2] + shift};
      };
      for (const Case& c : cases) {
        SCOPED_TRACE(c.name);
        const Triangle ma = map(a);
        const Triangle mb = map(c.b);
        if (shift[0] != 0.0 && !c.intersecting) {
          continue;  // a 2^-30 gap is below ulp(1e6): the shifted copies are not exact
        }
        expect_order_invariant_intersection(ma, mb, c.intersecting);
        const TriangleDistanceResult r = check_pair(ma, mb);
        EXPECT_EQ(r.kind == TriangleDistanceCase::Intersecting, c.intersecting);
      }
    }
  }
  // Known gaps.
  EXPECT_EQ(triangle_distance(a, cases[12].b).distance, g);  // vertex above face
  EXPECT_EQ(triangle_distance(a, cases[8].b).distance, g);   // coplanar gap at vertex
}

// The common point reported for touching triangles lies on both. Edge on edge, with
// coordinates that are not dyadic, the crossing point's clamping interval came out of signs
// that rounding flipped, and the point was a corner of one triangle 8.7e-4 away from the
// other (an audit's mesh, triangles of size 1e-3).
TEST(TriangleIntersection, ContactPointsLieOnBothTriangles) {
  auto check = [](const Triangle& a, const Triangle& b, double scale) {
    const TriangleDistanceResult r = triangle_distance(a, b);
    if (r.kind != TriangleDistanceCase::Intersecting) return false;
    const double tol = 1e-12 * scale;
    EXPECT_LE(std::sqrt(point_triangle_distance(r.point_a, a).squared_distance), tol);
    EXPECT_LE(std::sqrt(point_triangle_distance(r.point_a, b).squared_distance), tol);
    EXPECT_EQ(r.point_a, r.point_b);
    return true;
  };
  const Triangle a = {Vec3(0.0, 0.0015, 0.001), Vec3(0.002, 0.0, 0.0), Vec3(0.0, 0.0, 0.0017)};
  const Triangle b = {Vec3(0.0015, 0.0, 0.001), Vec3(0.0015, 0.0005, 0.0005), Vec3(0.001, 0.0005, 0.0)};
  EXPECT_TRUE(check(a, b, 1e-3));
  EXPECT_TRUE(check(b, a, 1e-3));
  // Edges crossing at a point of each, at scales whose coordinates are not dyadic.
  std::mt19937_64 rng(2025);
  std::uniform_real_distribution<double> unit(0.2, 0.8);
  int touching = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const double scale = trial % 3 == 0 ? 1e-3 : trial % 3 == 1 ? 1e-6 : 1.7;
    auto pt = [&] { return random_vec(rng, scale); };
    const Vec3 x = pt(), d = pt() - x, e = pt() - x;
    const double s = unit(rng), u = unit(rng);
    // Edge p0p1 of A and edge q0q1 of B both pass (up to rounding) through x.
    const Triangle ta = {x - s * d, x + (1 - s) * d, x + pt()};
    const Triangle tb = {x - u * e, x + (1 - u) * e, x + pt()};
    if (check(ta, tb, scale)) ++touching;
    check(tb, ta, scale);
  }
  EXPECT_GT(touching, 100);  // rounding leaves some apart; enough must touch to mean much
}

TEST(TriangleIntersection, DegenerateTrianglesAgainstEachOther) {
  const double g = std::ldexp(1.0, -30);
  const Triangle x_axis = {Vec3(-2, 0, 0), Vec3(2, 0, 0), Vec3(0, 0, 0)};
  const Triangle y_axis = {Vec3(0, -2, 0), Vec3(0, 2, 0), Vec3(0, 1, 0)};
  const Triangle y_axis_up = {Vec3(0, -2, g), Vec3(0, 2, g), Vec3(0, 1, g)};
  const Triangle point = {Vec3(1, 0, 0), Vec3(1, 0, 0), Vec3(1, 0, 0)};
  const Triangle point_off = {Vec3(1, g, 0), Vec3(1, g, 0), Vec3(1, g, 0)};
  const Triangle collinear_overlap = {Vec3(1, 0, 0), Vec3(5, 0, 0), Vec3(3, 0, 0)};
  const Triangle collinear_apart = {Vec3(2 + g, 0, 0), Vec3(5, 0, 0), Vec3(3, 0, 0)};
  const Triangle collinear_touch = {Vec3(2, 0, 0), Vec3(5, 0, 0), Vec3(3, 0, 0)};
  expect_order_invariant_intersection(x_axis, y_axis, true);
  expect_order_invariant_intersection(x_axis, y_axis_up, false);
  expect_order_invariant_intersection(x_axis, point, true);
  expect_order_invariant_intersection(x_axis, point_off, false);
  expect_order_invariant_intersection(point, point, true);
  expect_order_invariant_intersection(point, point_off, false);
  expect_order_invariant_intersection(x_axis, collinear_overlap, true);
  expect_order_invariant_intersection(x_axis, collinear_apart, false);
  expect_order_invariant_intersection(x_axis, collinear_touch, true);
  for (const Triangle* t : {&y_axis, &y_axis_up, &point, &point_off, &collinear_overlap,
                            &collinear_apart, &collinear_touch}) {
    check_pair(x_axis, *t);
  }
  EXPECT_EQ(triangle_distance(x_axis, y_axis_up).distance, g);
  EXPECT_EQ(triangle_distance(point, point_off).distance, g);
  EXPECT_EQ(triangle_distance(x_axis, collinear_apart).distance, g);
}

// ---- triangle distance ---------------------------------------------------------------------

TEST(TriangleDistance, RandomPairsMatchTwin) {
  std::mt19937_64 rng(31);
  std::uniform_real_distribution<double> unit01(0.0, 1.0);
  std::vector<int> intersecting;
  for (double offset : {0.0, 1e6}) {
    ErrorStats stats;
    const Vec3 shift = Vec3::Constant(offset);
    for (int trial = 0; trial < 4000; ++trial) {
      const double size = std::pow(10.0, 2 * unit01(rng) - 1);  // 0.1 .. 10
      const Triangle a = random_triangle(rng, shift, size);
      const Triangle b = random_triangle(rng, shift + random_vec(rng, 0.6 * size), size);
      check_pair(a, b, &stats);
      if (::testing::Test::HasFailure()) {
        FAIL() << "offset " << offset << " trial " << trial;
      }
    }
    stats.print(offset == 0.0 ? "random pairs" : "random pairs at 1e6");
    intersecting.push_back(stats.intersecting);
  }
  for (int count : intersecting) {  // a real mix of intersecting and separated pairs
    EXPECT_GT(count, 400);
    EXPECT_LT(count, 3600);
  }
}

TEST(TriangleDistance, AdversarialShapesMatchTwin) {
  // Degenerate and nearly degenerate triangles, parallel and nearly parallel edges and faces,
  // at the origin and at 1e6.
  std::mt19937_64 rng(32);
  std::uniform_real_distribution<double> unit01(0.0, 1.0);
  for (double offset : {0.0, 1e6}) {
    ErrorStats stats;
    const Vec3 shift = Vec3::Constant(offset);
    for (int trial = 0; trial < 6000; ++trial) {
      Triangle a = random_triangle(rng, shift, 1.0);
      Triangle b = random_triangle(rng, shift + random_vec(rng, 1.5), 1.0);
      const double tiny = std::pow(10.0, -15 * unit01(rng));
      switch (trial % 10) {
        case 0: a[2] = a[0] + 0.5 * (a[1] - a[0]); break;                     // collinear
        case 1: a[1] = a[0]; b[2] = b[1]; break;                               // repeated
        case 2: a[1] = a[0]; a[2] = a[0]; break;                               // point
        case 3: a[2] = a[0] + (1 + tiny) * (a[1] - a[0]); break;               // cap sliver
        case 4: b[1] = b[0] + (a[1] - a[0]); break;                            // parallel edges
        case 5: b[1] = b[0] + (a[1] - a[0]) + tiny * random_vec(rng, 1.0); break;  // nearly
        case 6: {                                                              // parallel faces
          const Vec3 up = random_vec(rng, 0.3);
          b = {a[0] + up, a[1] + up + 0.2 * (a[2] - a[1]), a[2] + up};
          break;
        }
        case 7: {                                                              // nearly coplanar
          const Vec3 n = (a[1] - a[0]).cross(a[2] - a[0]);
          const Vec3 in_plane = 0.3 * (a[1] - a[0]) + 0.4 * (a[2] - a[0]);
          b = {a[0] + in_plane, a[1] + in_plane + tiny * n, a[2] + 1.2 * in_plane - tiny * n};
          break;
        }
        case 8: {  // edge nearly touching an edge, nearly parallel
          const Vec3 e = a[1] - a[0];
          b[0] = a[0] + 0.5 * e + tiny * random_vec(rng, 1.0);
          b[1] = b[0] + 0.8 * e + tiny * random_vec(rng, 1.0);
          break;
        }
        default: b[2] = b[0]; b[1] = b[0]; break;                              // point b
      }
      check_pair(a, b, &stats);
      if (::testing::Test::HasFailure()) {
        FAIL() << "offset " << offset << " trial " << trial;
      }
    }
    stats.print(offset == 0.0 ? "adversarial" : "adversarial at 1e6");
  }
}

// ---- separation lower bound ----------------------------------------------------------------

/// The separation bound computed pair by pair as its header states it, every axis from the
/// two triangles' corners: the twin of separation_lower_bound(), which takes each triangle's
/// own part from a SeparationSite computed once per triangle.
double twin_separation(const Triangle& a, const Triangle& b) {
  auto gap = [&](const Vec3& w) {
    const double ww = w.squaredNorm();
    if (!(ww >= 0x1p-900) || !std::isfinite(ww)) return -kInfinity;
    const ProjectionGaps g = projection_gaps(a, b, w);
    const double q = std::max(g.b_above_a, g.a_above_b) / std::sqrt(ww);
    return std::isfinite(q) ? q : -kInfinity;
  };
  const Vec3 centres = (b[0] + b[1] + b[2]) - (a[0] + a[1] + a[2]);
  const double g0 = gap((a[1] - a[0]).cross(a[2] - a[0]));
  const double g1 = gap((b[1] - b[0]).cross(b[2] - b[0]));
  return std::max(std::max(g0, g1), gap(centres));
}

/// separation_lower_bound(a, b) is its twin's value bitwise, symmetric bitwise, and never
/// above the twin distance by more than its documented rounding bound 2^-48 S. Returns
/// whether it is positive.
bool check_separation(const Triangle& a, const Triangle& b) {
  const double lb = separation_lower_bound(a, b), lb_swapped = separation_lower_bound(b, a);
  const double lb_twin = twin_separation(a, b);
  EXPECT_EQ(std::memcmp(&lb, &lb_twin, sizeof lb), 0) << "not the twin's value: " << lb << " vs " << lb_twin;
  EXPECT_EQ(std::memcmp(&lb, &lb_swapped, sizeof lb), 0) << "not symmetric";
  const Real twin = twin_hull_distance(as_points(a), as_points(b)).distance;
  EXPECT_LE(static_cast<Real>(lb), twin + static_cast<Real>(0x1p-48 * scale_of(a, b)))
      << "lower bound " << lb << " above the distance " << static_cast<double>(twin);
  return lb > 0;
}

TEST(SeparationBound, NeverAboveTheTwinDistance) {
  std::mt19937_64 rng(33);
  std::uniform_real_distribution<double> unit01(0.0, 1.0);
  for (double offset : {0.0, 1e6}) {
    const Vec3 shift = Vec3::Constant(offset);
    int positive = 0;
    for (int trial = 0; trial < 6000; ++trial) {
      const double size = std::pow(10.0, 2 * unit01(rng) - 1);  // 0.1 .. 10
      Triangle a = random_triangle(rng, shift, size);
      Triangle b = random_triangle(rng, shift + random_vec(rng, 1.5 * size), size);
      const double tiny = std::pow(10.0, -15 * unit01(rng));
      const Vec3 n = (a[1] - a[0]).cross(a[2] - a[0]);
      switch (trial % 8) {
        case 0: a[2] = a[0] + 0.5 * (a[1] - a[0]); break;              // collinear
        case 1: a[1] = a[0]; a[2] = a[0]; break;                        // a point
        case 2: a[2] = a[0] + (1 + tiny) * (a[1] - a[0]); break;        // cap sliver
        case 3: {                                                       // stacked, parallel
          const Vec3 up = (tiny * size / n.norm()) * n;
          b = {a[0] + up, a[1] + up, a[2] + up};
          break;
        }
        case 4: {                                                       // nearly coplanar
          const Vec3 in_plane = 0.3 * (a[1] - a[0]) + 0.4 * (a[2] - a[0]);
          b = {a[0] + in_plane, a[1] + in_plane + tiny * n, a[2] + 1.2 * in_plane - tiny * n};
          break;
        }
        case 5: b = a; break;                                           // identical
        default: break;                                                 // random
      }
      positive += check_separation(a, b);
      if (::testing::Test::HasFailure()) FAIL() << "offset " << offset << " trial " << trial;
    }
    std::printf("[ info     ] separation bound positive on %d of 6000 pairs (offset %g)\n",
                positive, offset);
    EXPECT_GT(positive, 1000);  // not a vacuous bound
  }
}

TEST(SeparationBound, SitesGiveThePairsValueAtEveryScale) {
  // From 2^-1000 to 2^1000, near the origin and up to 2^1020 from it (overflowing axes and
  // projections, underflowing axes, subnormal coordinates): the value from the per-triangle
  // sites is the pair-by-pair twin's, bitwise, whichever triangle comes first.
  std::mt19937_64 rng(34);
  std::uniform_real_distribution<double> unit01(0.0, 1.0);
  int positive = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    const double scale = std::ldexp(1.0, static_cast<int>(2000 * unit01(rng)) - 1000);
    Triangle a = random_triangle(rng, Vec3::Zero(), 1.0);
    Triangle b = random_triangle(rng, random_vec(rng, 1.5), 1.0);
    if (trial % 4 == 1) b = {a[0] + Vec3(0, 0, 0.5), a[1] + Vec3(0, 0, 0.5), a[2] + Vec3(0, 0, 0.5)};
    if (trial % 4 == 2) a[2] = a[0];
    // Every fourth pair far from the origin: small triangles there overflow projections
    // onto axes that themselves stay finite.
    const Vec3 far = trial % 4 == 3 ? Vec3(std::ldexp(1.0, static_cast<int>(1020 * unit01(rng))), 0, 0) : Vec3::Zero();
    for (auto* t : {&a, &b})
      for (Vec3& p : *t) p = p * scale + far;
    const double lb = separation_lower_bound(a, b), lb_swapped = separation_lower_bound(b, a);
    const double twin = twin_separation(a, b);
    ASSERT_EQ(std::memcmp(&lb, &twin, sizeof lb), 0) << "trial " << trial << ": " << lb << " vs " << twin;
    ASSERT_EQ(std::memcmp(&lb, &lb_swapped, sizeof lb), 0) << "trial " << trial;
    positive += lb > 0;
  }
  EXPECT_GT(positive, 500);  // not a vacuous comparison
}

TEST(SeparationBound, TightAlongTheSeparatingDirection) {
  // Parallel triangles h apart along the normal, and triangles h apart along x with faces
  // facing each other: the bound finds (almost) the whole gap.
  const Triangle a{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
  for (double h : {1e-9, 1e-3, 0.5, 7.0}) {
    const Vec3 up(0, 0, h);
    const Triangle b{a[0] + up, a[1] + up, a[2] + up};
    EXPECT_GE(separation_lower_bound(a, b), h * (1 - 1e-12)) << h;
    const Triangle c{Vec3(1 + h, 0, 0), Vec3(1 + h, 1, 0), Vec3(1 + h, 0, 1)};
    EXPECT_GT(separation_lower_bound(a, c), 0.5 * h) << h;
  }
  // Touching and crossing triangles: nothing to separate.
  const Triangle touching{Vec3(1, 0, 0), Vec3(2, 0, 0), Vec3(2, 1, 0)};
  EXPECT_LE(separation_lower_bound(a, touching), 0.0);
  const Triangle crossing{Vec3(0.2, 0.2, -1), Vec3(0.2, 0.2, 1), Vec3(0.3, 0.1, 0)};
  EXPECT_LE(separation_lower_bound(a, crossing), 0.0);
  // Far outside the supported range the projections overflow: no bound, never a wrong one.
  const double big = 1e290;
  const Triangle huge{big * a[0], big * a[1], big * a[2]};
  const Triangle huge_up{huge[0] + Vec3(0, 0, big), huge[1] + Vec3(0, 0, big), huge[2] + Vec3(0, 0, big)};
  const double lb = separation_lower_bound(huge, huge_up), lb_twin = twin_separation(huge, huge_up);
  EXPECT_FALSE(std::isnan(lb));
  EXPECT_LE(lb, big);
  EXPECT_EQ(std::memcmp(&lb, &lb_twin, sizeof lb), 0) << lb << " vs " << lb_twin;
}

TEST(TriangleDistance, KnownFeaturesAndTieOrder) {
  // b floats parallel above a, all its corners over a's interior: the three FaceVertex
  // candidates tie at exactly 1; the first (b0) wins.
  const Triangle a = {Vec3(0, 0, 0), Vec3(8, 0, 0), Vec3(0, 8, 0)};
  const Triangle b = {Vec3(1, 1, 1), Vec3(3, 1, 1), Vec3(1, 3, 1)};
  TriangleDistanceResult r = triangle_distance(a, b);
  EXPECT_EQ(r.distance, 1.0);
  EXPECT_EQ(r.kind, TriangleDistanceCase::FaceVertex);
  EXPECT_EQ(r.feature_b, 0);
  EXPECT_EQ(r.point_a, Vec3(1, 1, 0));
  EXPECT_EQ(r.point_b, Vec3(1, 1, 1));
  r = triangle_distance(b, a);  // mirrored: VertexFace a0
  EXPECT_EQ(r.kind, TriangleDistanceCase::VertexFace);
  EXPECT_EQ(r.feature_a, 0);
  // Coplanar, parallel facing edges at distance 1: VF a1, FV b0 and EE (0,0) all give 1; VF
  // comes first.
  const Triangle c = {Vec3(0, 0, 0), Vec3(2, 0, 0), Vec3(1, -3, 0)};
  const Triangle d = {Vec3(1, 1, 0), Vec3(3, 1, 0), Vec3(2, 4, 0)};
  r = triangle_distance(c, d);
  EXPECT_EQ(r.distance, 1.0);
  EXPECT_EQ(r.kind, TriangleDistanceCase::VertexFace);
  EXPECT_EQ(r.feature_a, 1);
  // Skew crossing edges: EdgeEdge (edge 0 of each).
  const Triangle e = {Vec3(-1, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, -3)};
  const Triangle f = {Vec3(0, -1, 1), Vec3(0, 1, 1), Vec3(0, 0, 4)};
  r = triangle_distance(e, f);
  EXPECT_EQ(r.distance, 1.0);
  EXPECT_EQ(r.kind, TriangleDistanceCase::EdgeEdge);
  EXPECT_EQ(r.feature_a, 0);
  EXPECT_EQ(r.feature_b, 0);
  EXPECT_EQ(r.point_a, Vec3(0, 0, 0));
  EXPECT_EQ(r.point_b, Vec3(0, 0, 1));
  // Intersecting: distance exactly 0, no features, one common point.
  const Triangle g = {Vec3(1, 1, -1), Vec3(1, 1, 1), Vec3(5, 5, 3)};
  r = triangle_distance(a, g);
  EXPECT_EQ(r.distance, 0.0);
  EXPECT_EQ(r.kind, TriangleDistanceCase::Intersecting);
  EXPECT_EQ(r.point_a, Vec3(1, 1, 0));
  EXPECT_EQ(r.point_b, r.point_a);
}

TEST(TriangleDistance, ZeroOnlyForTouchingPairs) {
  // Found by an independent exact oracle: the apex of b lies 1.23e-17 below a (an exact
  // rational computation), which the coordinate differences round away, so the distance
  // computed as 0 although the exact predicates say the triangles are apart.
  const Triangle a = {Vec3(0.0, 0.0, -0.99), Vec3(1.0, 0.0, -0.05), Vec3(0.0, 1.0, -0.57)};
  const Triangle b = {Vec3(0.09, 0.37, -0.75), Vec3(-0.010000000000000009, 0.27, -1.25),
                      Vec3(0.29000000000000004, 0.32, -1.25)};
  ASSERT_FALSE(triangles_intersect(a, b));
  TriangleDistanceResult r = triangle_distance(a, b);
  EXPECT_EQ(r.distance, std::numeric_limits<double>::denorm_min());
  EXPECT_NE(r.kind, TriangleDistanceCase::Intersecting);
  // Corners of b placed on a's plane by rounded barycentric combinations: some land exactly
  // on it (touching), most within rounding of it on either side. Distance 0 exactly when the
  // exact predicates find a common point.
  std::mt19937_64 rng(35);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int touching = 0, rounded_apart = 0;
  for (int trial = 0; trial < 20000; ++trial) {
    const Triangle c = random_triangle(rng, Vec3::Zero(), 1.0);
    const double u = 0.5 * unit(rng), v = 0.5 * unit(rng);
    const Vec3 p = c[0] + u * (c[1] - c[0]) + v * (c[2] - c[0]);
    const Vec3 n = (c[1] - c[0]).cross(c[2] - c[0]).normalized();
    const double side = trial % 2 == 0 ? 1.0 : -1.0;
    const Triangle d = {p, p + side * n + random_vec(rng, 0.3), p + side * n + random_vec(rng, 0.3)};
    const bool hit = triangles_intersect(c, d);
    r = triangle_distance(c, d);
    ASSERT_EQ(r.distance == 0.0, hit) << "trial " << trial << ": distance " << r.distance;
    ASSERT_EQ(r.kind == TriangleDistanceCase::Intersecting, hit) << "trial " << trial;
    touching += hit;
    rounded_apart += !hit && r.distance == std::numeric_limits<double>::denorm_min();
  }
  std::printf("[ info ] 20000 corners on a plane: %d touching, %d apart by less than rounding\n",
              touching, rounded_apart);
  EXPECT_GT(touching, 0);
  EXPECT_GT(rounded_apart, 0);
}

TEST(TriangleDistance, DeterministicBitwise) {
  std::mt19937_64 rng(33);
  for (int trial = 0; trial < 2000; ++trial) {
    const Triangle a = random_triangle(rng, Vec3::Zero(), 1.0);
    const Triangle b = random_triangle(rng, random_vec(rng, 2.0), 1.0);
    const TriangleDistanceResult r1 = triangle_distance(a, b);
    const TriangleDistanceResult r2 = triangle_distance(a, b);
    ASSERT_EQ(std::memcmp(&r1.distance, &r2.distance, sizeof(double)), 0);
    ASSERT_EQ(r1.point_a, r2.point_a);
    ASSERT_EQ(r1.point_b, r2.point_b);
    ASSERT_EQ(r1.kind, r2.kind);
    ASSERT_EQ(r1.feature_a, r2.feature_a);
    ASSERT_EQ(r1.feature_b, r2.feature_b);
    // Swapping the arguments gives the same distance up to rounding.
    ASSERT_NEAR(triangle_distance(b, a).distance, r1.distance, kTolUlps * kEpsilon * scale_of(a, b));
  }
}

/// The triangles of a bumpy height field over an n x n grid of vertices (spacing 1), with
/// coordinates times `scale` plus `offset`; `integer` keeps them on the integer grid (many
/// candidates of a pair then tie exactly), otherwise they are jittered.
std::vector<std::array<int, 3>> height_field(int n, std::vector<Vec3>& vertices, std::mt19937_64& rng, bool integer,
                                             double scale, double offset) {
  std::uniform_real_distribution<double> jitter(-0.3, 0.3);
  vertices.clear();
  for (int i = 0; i < n; ++i) {
    for (int j = 0; j < n; ++j) {
      Vec3 p(i, j, std::round(2 * std::sin(0.7 * i) * std::cos(0.5 * j)));
      if (!integer) p += Vec3(jitter(rng), jitter(rng), jitter(rng));
      vertices.push_back(p * scale + Vec3::Constant(offset));
    }
  }
  std::vector<std::array<int, 3>> faces;
  for (int i = 0; i + 1 < n; ++i) {
    for (int j = 0; j + 1 < n; ++j) {
      const int v = i * n + j;
      faces.push_back({v, v + n, v + 1});
      faces.push_back({v + 1, v + n, v + n + 1});
    }
  }
  return faces;
}

TEST(TriangleDistance, PruningOnMeshNeighboursIsTheFullSearch) {
  // Where the pruning skips most candidates: triangles of one mesh that share no vertex and
  // lie within a few edges of each other (the pairs of the intra-object distance), on the
  // integer grid (exact ties between candidates) and jittered, at scales 2^-100 to 2^100 and
  // far from the origin. Every result must be bitwise that of the search over all 15.
  std::mt19937_64 rng(35);
  int pairs = 0;
  for (bool integer : {true, false}) {
    for (auto [scale, offset] : {std::pair{1.0, 0.0}, std::pair{0x1p-100, 0.0}, std::pair{0x1p100, 0.0},
                                 std::pair{1.0, 1e6}, std::pair{1e-3, 1e3}}) {
      std::vector<Vec3> v;
      const auto faces = height_field(10, v, rng, integer, scale, offset);
      for (size_t f = 0; f < faces.size(); ++f) {
        for (size_t g = 0; g < faces.size(); ++g) {
          bool shared = false;
          for (int x : faces[f])
            for (int y : faces[g]) shared |= x == y;
          const Triangle a{v[faces[f][0]], v[faces[f][1]], v[faces[f][2]]};
          const Triangle b{v[faces[g][0]], v[faces[g][1]], v[faces[g][2]]};
          if (f == g || shared || (a[0] - b[0]).norm() > 3.5 * scale) continue;
          expect_same_as_unpruned(a, b, triangle_distance(a, b));
          ++pairs;
          if (::testing::Test::HasFailure()) FAIL() << "integer " << integer << " scale " << scale << " pair " << f << ", " << g;
        }
      }
    }
  }
  EXPECT_GT(pairs, 10000);
}

/// Micro-benchmark, not a test: run with
///   tests_core --gtest_also_run_disabled_tests --gtest_filter='*DISABLED_Benchmark*'
/// Each chunk of 32 pairs is timed separately and its fastest of many rounds is kept: this
/// drops preemption on a shared machine, while the 8192 distinct pairs between two visits of
/// a chunk keep the branch predictor from learning the data.
TEST(TriangleDistance, DISABLED_Benchmark) {
  std::mt19937_64 rng(34);
  constexpr int kChunk = 32;
  constexpr int kRounds = 100;
  // ns per call of f over the pairs (the fastest of kRounds per chunk, summed).
  auto time_calls = [&](const std::vector<std::pair<Triangle, Triangle>>& pairs, auto f) {
    const size_t chunks = pairs.size() / kChunk;
    std::vector<double> fastest(chunks, kInfinity);
    double sink = 0;
    for (int round = 0; round < kRounds; ++round) {
      for (size_t c = 0; c < chunks; ++c) {
        const auto start = std::chrono::steady_clock::now();
        for (size_t i = c * kChunk; i < (c + 1) * kChunk; ++i) sink += f(pairs[i].first, pairs[i].second).distance;
        const std::chrono::duration<double, std::nano> elapsed = std::chrono::steady_clock::now() - start;
        fastest[c] = std::min(fastest[c], elapsed.count());
      }
    }
    double total = 0;
    for (double t : fastest) total += t;
    return sink >= 0 ? total / static_cast<double>(chunks * kChunk) : 0.0;
  };
  auto report = [&](const char* name, const std::vector<std::pair<Triangle, Triangle>>& pairs) {
    int intersecting = 0;
    for (const auto& [a, b] : pairs) intersecting += triangles_intersect(a, b);
    std::printf("[ bench ] %s: %.1f ns per triangle_distance call, %.1f without pruning (%d of %zu pairs intersect)\n",
                name, time_calls(pairs, [](const Triangle& a, const Triangle& b) { return triangle_distance(a, b); }),
                time_calls(pairs, [](const Triangle& a, const Triangle& b) { return detail::triangle_distance_unpruned(a, b); }),
                intersecting, pairs.size());
  };
  auto random_pairs = [&](double spread) {
    std::vector<std::pair<Triangle, Triangle>> pairs;
    for (int i = 0; i < 8192; ++i) pairs.emplace_back(random_triangle(rng, Vec3::Zero(), 1.0), random_triangle(rng, random_vec(rng, spread), 1.0));
    return pairs;
  };
  report("nearby (unit triangles, centres within +-2)", random_pairs(2.0));
  report("touching range (centres within +-1)", random_pairs(1.0));
  report("separated (centres within +-6)", random_pairs(6.0));
  // The intra-object distance's pairs: triangles of one jittered height field that share no
  // vertex, within a few edges of each other, in a shuffled order.
  std::vector<Vec3> v;
  const auto faces = height_field(40, v, rng, false, 1.0, 0.0);
  std::vector<std::pair<Triangle, Triangle>> mesh;
  for (size_t f = 0; f < faces.size(); ++f) {
    for (size_t g = f + 1; g < faces.size(); ++g) {
      bool shared = false;
      for (int x : faces[f])
        for (int y : faces[g]) shared |= x == y;
      const Triangle a{v[faces[f][0]], v[faces[f][1]], v[faces[f][2]]};
      const Triangle b{v[faces[g][0]], v[faces[g][1]], v[faces[g][2]]};
      if (!shared && (a[0] - b[0]).norm() <= 2.5) mesh.emplace_back(a, b);
    }
  }
  std::shuffle(mesh.begin(), mesh.end(), rng);
  mesh.resize(std::min<size_t>(mesh.size(), 8192));
  report("mesh neighbours (non-adjacent, within 2.5 edges)", mesh);
}

}  // namespace
}  // namespace vproxq
