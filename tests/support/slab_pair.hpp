#pragma once
// Triangle pairs whose distance is known exactly, for the distance primitives' tests and the
// fuzz harness tests/fuzz/fuzz_distance.cpp.
//
// The construction: an integer normal n = (nx, ny, 1) and a slab between the planes n.x = 0
// and n.x = m |n|^2 (m >= 0 an integer). Triangle A lies in n.x <= 0 with 1, 2 or 3 corners on
// the plane n.x = 0 (its top feature: a vertex, an edge or the face), triangle B in
// n.x >= m |n|^2 with 1-3 corners on that plane. A point of the plane n.x = 0 is (x, y,
// -nx x - ny y) for integers x, y, and B's top corners are such points moved by m n. Every
// pair of points of A and B is at least m |n| apart (the slab's width), with equality exactly
// for a point of A's top feature and a point of B's top feature that differ by m n, i.e. whose
// (x, y) agree. So:
//   - if the (x, y) hulls of the two top features meet (decided exactly in integers), the
//     distance is m |n|, and for m = 0 the triangles touch;
//   - otherwise it is larger than m |n|, and for m = 0 the triangles do not touch.
// The same holds for every feature pair (a corner or edge of A against a corner, edge or B
// itself): at least m |n|, and exactly m |n| when both features are on the top planes and
// their (x, y) hulls meet.
//
// The integers are drawn so that needles (corners a few units apart beside edges up to 2^44
// long), caps (a corner next to the line through two others), repeated corners, collinear
// triangles, corners exactly on the other triangle's edges, corners just past a needle's tip
// (away from both other corners), parallel edges and faces are common. The points are then
// permuted and mirrored along the axes, moved by an integer offset of up to 2^51 and scaled by
// 2^j, j in [-60, 60]: every coordinate is an integer below 2^53 times a power of two, so the
// whole construction is exact in double precision.
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <cstdint>
#include <limits>
#include <optional>
#include <sstream>
#include <string>

#include "core/geometry/point_triangle.hpp"
#include "core/geometry/segment_segment.hpp"
#include "core/geometry/triangle_distance.hpp"
#include "core/types.hpp"

namespace vproxq::test {

/// A point of the (x, y) parameter plane.
struct Int2 {
  std::int64_t x = 0, y = 0;
};

/// 128-bit integers (GCC and clang; __extension__ keeps -Wpedantic quiet).
__extension__ using Int128 = __int128;

/// Sign of the orientation of (p, q, r), exactly (|coordinates| < 2^60).
inline int orient2(const Int2& p, const Int2& q, const Int2& r) {
  const Int128 d = static_cast<Int128>(q.x - p.x) * (r.y - p.y) -
                   static_cast<Int128>(q.y - p.y) * (r.x - p.x);
  return (d > 0) - (d < 0);
}

/// r lies in the bounding box of p and q (used for collinear points).
inline bool in_box(const Int2& p, const Int2& q, const Int2& r) {
  return std::min(p.x, q.x) <= r.x && r.x <= std::max(p.x, q.x) && std::min(p.y, q.y) <= r.y &&
         r.y <= std::max(p.y, q.y);
}

/// The closed segments [p, q] and [r, s] meet (either may be a point).
inline bool segments_meet(const Int2& p, const Int2& q, const Int2& r, const Int2& s) {
  const int o1 = orient2(p, q, r), o2 = orient2(p, q, s);
  const int o3 = orient2(r, s, p), o4 = orient2(r, s, q);
  if (o1 * o2 < 0 && o3 * o4 < 0) return true;
  return (o1 == 0 && in_box(p, q, r)) || (o2 == 0 && in_box(p, q, s)) ||
         (o3 == 0 && in_box(r, s, p)) || (o4 == 0 && in_box(r, s, q));
}

/// p lies in the closed triangle (t0, t1, t2), which must not be collinear.
inline bool in_triangle(const Int2& p, const Int2& t0, const Int2& t1, const Int2& t2) {
  const int s0 = orient2(t0, t1, p), s1 = orient2(t1, t2, p), s2 = orient2(t2, t0, p);
  return (s0 >= 0 && s1 >= 0 && s2 >= 0) || (s0 <= 0 && s1 <= 0 && s2 <= 0);
}

/// The convex hulls of 1-3 points each meet: an edge of one meets an edge of the other (a
/// point is a zero-length edge; a collinear triangle is the union of its edges), or a corner
/// of one lies in the other, non-collinear, triangle.
inline bool hulls_meet(const Int2* p, int np, const Int2* q, int nq) {
  // Edge k joins corner k and corner k+1 (mod the count): one edge for 1 or 2 corners.
  const int ep = np == 3 ? 3 : 1, eq = nq == 3 ? 3 : 1;
  for (int i = 0; i < ep; ++i) {
    for (int j = 0; j < eq; ++j) {
      if (segments_meet(p[i], p[(i + 1) % np], q[j], q[(j + 1) % nq])) return true;
    }
  }
  if (nq == 3 && orient2(q[0], q[1], q[2]) != 0 && in_triangle(p[0], q[0], q[1], q[2])) return true;
  if (np == 3 && orient2(p[0], p[1], p[2]) != 0 && in_triangle(q[0], p[0], p[1], p[2])) return true;
  return false;
}

/// Squared distance between the point p and the segment [a, b] of the plane n.x = 0, where
/// (x, y) stands for (x, y, -nx x - ny y): the region (an end or the interior) is decided
/// exactly in integers, the value is rounded once or twice in long double (|w x d|^2 / |d|^2
/// by Lagrange's identity, without cancellation).
inline long double plane_point_segment_sq(const Int2& p, const Int2& a, const Int2& b, std::int64_t nx,
                                          std::int64_t ny) {
  auto lift = [&](std::int64_t dx, std::int64_t dy) {
    return std::array<Int128, 3>{dx, dy, -static_cast<Int128>(nx) * dx - static_cast<Int128>(ny) * dy};
  };
  auto dot = [](const std::array<Int128, 3>& u, const std::array<Int128, 3>& v) {
    return u[0] * v[0] + u[1] * v[1] + u[2] * v[2];
  };
  auto norm_sq = [](const std::array<Int128, 3>& u) {
    long double sum = 0;
    for (const Int128 c : u) sum += static_cast<long double>(c) * static_cast<long double>(c);
    return sum;
  };
  const std::array<Int128, 3> w = lift(p.x - a.x, p.y - a.y), d = lift(b.x - a.x, b.y - a.y);
  const Int128 along = dot(w, d), length_sq = dot(d, d);
  if (along <= 0) return norm_sq(w);
  if (along >= length_sq) return norm_sq(lift(p.x - b.x, p.y - b.y));
  const std::array<Int128, 3> cross = {w[1] * d[2] - w[2] * d[1], w[2] * d[0] - w[0] * d[2],
                                       w[0] * d[1] - w[1] * d[0]};
  return norm_sq(cross) / static_cast<long double>(length_sq);
}

/// Squared distance between the convex hulls of 1-3 points each in the plane n.x = 0: 0 when
/// they meet, else the least distance of a corner of one to an edge of the other (disjoint
/// convex sets are closest at a corner of one of them).
inline long double plane_hull_distance_sq(const Int2* p, int np, const Int2* q, int nq, std::int64_t nx,
                                          std::int64_t ny) {
  if (hulls_meet(p, np, q, nq)) return 0;
  long double best = std::numeric_limits<long double>::infinity();
  for (int side = 0; side < 2; ++side) {
    const Int2* corners = side == 0 ? p : q;
    const Int2* other = side == 0 ? q : p;
    const int nc = side == 0 ? np : nq, no = side == 0 ? nq : np;
    for (int i = 0; i < nc; ++i)
      for (int k = 0; k < no; ++k)
        best = std::min(best, plane_point_segment_sq(corners[i], other[k], other[(k + 1) % no], nx, ny));
  }
  return best;
}

/// One constructed pair.
struct SlabPair {
  Triangle a, b;
  std::array<bool, 3> top_a{}, top_b{};  ///< which corners lie on their slab plane
  std::array<Int2, 3> xy_a{}, xy_b{};    ///< each corner's (x, y) parameter (top corners only meaningful)
  std::int64_t m = 0;                    ///< slab width in units of |n|
  std::int64_t nx = 0, ny = 0;           ///< n = (nx, ny, 1) before the axes are permuted
  int power = 0;                         ///< the scale 2^power
  long double gap = 0;                   ///< the slab's width m |n| 2^j (rounded in long double)
  Vec3 unit_normal = Vec3::Zero();       ///< from A towards B, in the final axes
  double scale = 1;                      ///< S: the largest coordinate magnitude (1 if all are 0)
  std::string recipe;                    ///< the integers, for failure messages
};

/// Whether the (x, y) hulls of the two top features meet: then the distance is the slab's
/// width, and for m = 0 the triangles touch.
inline bool top_features_meet(const SlabPair& s) {
  std::array<Int2, 3> ta, tb;
  int na = 0, nb = 0;
  for (std::size_t c = 0; c < 3; ++c) {
    if (s.top_a[c]) ta[static_cast<std::size_t>(na++)] = s.xy_a[c];
    if (s.top_b[c]) tb[static_cast<std::size_t>(nb++)] = s.xy_b[c];
  }
  return hulls_meet(ta.data(), na, tb.data(), nb);
}

/// Builds a pair from integers drawn by `pick(lo, hi)` (uniform or from fuzz bytes; each call
/// returns an integer in [lo, hi]).
template <class Pick>
SlabPair make_slab_pair(Pick&& pick) {
  std::ostringstream recipe;
  const int bits = static_cast<int>(pick(2, 44));
  const std::int64_t span = std::int64_t{1} << bits;
  const std::int64_t nx = pick(-3, 3), ny = pick(-3, 3);
  const std::int64_t nn = nx * nx + ny * ny + 1;
  std::int64_t m = 0;
  switch (pick(0, 3)) {
    case 0: m = 0; break;  // touching or not
    case 1: m = pick(1, 3); break;
    default: m = pick(1, span); break;
  }
  const int top_count_a = static_cast<int>(pick(1, 3)), top_count_b = static_cast<int>(pick(1, 3));
  recipe << "bits " << bits << " n (" << nx << "," << ny << ",1) m " << m << " tops " << top_count_a
         << "," << top_count_b;
  // Six (x, y, depth) triples, A's corners then B's; the first top_count of each are on top.
  std::array<Int2, 6> xy;
  std::array<std::int64_t, 6> depth{};
  for (int i = 0; i < 6; ++i) {
    const bool top = i < 3 ? i < top_count_a : i - 3 < top_count_b;
    const int mode = i == 0 ? 0 : static_cast<int>(pick(0, 5));
    Int2 p;
    if (mode == 5) {  // beyond an earlier point q, away from two others r, s: past a needle's tip
      const Int2 q = xy[static_cast<std::size_t>(pick(0, i - 1))];
      const Int2 r = xy[static_cast<std::size_t>(pick(0, i - 1))];
      const Int2 t = xy[static_cast<std::size_t>(pick(0, i - 1))];
      const std::int64_t den = std::int64_t{1} << pick(0, bits), num = pick(1, 4);
      p.x = q.x - (r.x + t.x - 2 * q.x) / den * num + (pick(0, 2) == 0 ? pick(-1, 1) : 0);
      p.y = q.y - (r.y + t.y - 2 * q.y) / den * num + (pick(0, 2) == 0 ? pick(-1, 1) : 0);
    } else if (mode <= 1) {  // fresh
      p.x = pick(-span, span);
      p.y = pick(-span, span);
    } else if (mode == 2) {  // next to an earlier point: needles and repeated corners
      const Int2 q = xy[static_cast<std::size_t>(pick(0, i - 1))];
      p.x = q.x + pick(-2, 2);
      p.y = q.y + pick(-2, 2);
    } else {  // on or beside the line through two earlier points: caps, corners on edges
      const Int2 q = xy[static_cast<std::size_t>(pick(0, i - 1))];
      const Int2 r = xy[static_cast<std::size_t>(pick(0, i - 1))];
      const std::int64_t den = pick(1, 8), num = pick(-2, 10);
      const bool exact = pick(0, 1) == 0;
      p.x = q.x + (r.x - q.x) / den * num + (exact ? 0 : pick(-1, 1));
      p.y = q.y + (r.y - q.y) / den * num + (exact ? 0 : pick(-1, 1));
    }
    p.x = std::clamp(p.x, -2 * span, 2 * span);
    p.y = std::clamp(p.y, -2 * span, 2 * span);
    xy[static_cast<std::size_t>(i)] = p;
    depth[static_cast<std::size_t>(i)] = top ? 0 : pick(0, 1) == 0 ? pick(1, 3) : pick(1, span);
    recipe << " (" << p.x << "," << p.y << "," << depth[static_cast<std::size_t>(i)] << ")";
  }
  // Integer points: A's below the plane n.x = 0, B's above n.x = m |n|^2.
  using I3 = std::array<std::int64_t, 3>;
  std::array<I3, 6> pts;
  for (int i = 0; i < 6; ++i) {
    const Int2 p = xy[static_cast<std::size_t>(i)];
    const std::int64_t k = depth[static_cast<std::size_t>(i)];
    const std::int64_t z = -nx * p.x - ny * p.y;
    pts[static_cast<std::size_t>(i)] =
        i < 3 ? I3{p.x, p.y, z - k} : I3{p.x + m * nx, p.y + m * ny, z + k + m};
  }
  // Corner order within each triangle (a rotation and a reflection), axes, offset, scale.
  const int order_a = static_cast<int>(pick(0, 5)), order_b = static_cast<int>(pick(0, 5));
  const int axes = static_cast<int>(pick(0, 47));
  const int offset_bits = static_cast<int>(pick(0, 51));
  const std::int64_t reach = (std::int64_t{1} << offset_bits) - 1;
  const I3 offset = {pick(-reach, reach), pick(-reach, reach), pick(-reach, reach)};
  const int power = static_cast<int>(pick(-60, 60));
  recipe << " orders " << order_a << "," << order_b << " axes " << axes << " offset (" << offset[0]
         << "," << offset[1] << "," << offset[2] << ") 2^" << power;
  static constexpr int kPerm[6][3] = {{0, 1, 2}, {1, 2, 0}, {2, 0, 1}, {0, 2, 1}, {2, 1, 0}, {1, 0, 2}};
  const int* axis_perm = kPerm[axes % 6];
  const int signs = axes / 6;  // bit k: mirror axis k
  auto place = [&](const I3& p) {
    Vec3 out;
    for (int k = 0; k < 3; ++k) {
      const double v = static_cast<double>(p[static_cast<std::size_t>(axis_perm[k])] + offset[static_cast<std::size_t>(k)]);
      out[k] = std::ldexp((signs >> k) & 1 ? -v : v, power);
    }
    return out;
  };
  SlabPair s;
  for (int c = 0; c < 3; ++c) {
    const int from_a = kPerm[order_a][c], from_b = kPerm[order_b][c];
    s.a[static_cast<std::size_t>(c)] = place(pts[static_cast<std::size_t>(from_a)]);
    s.b[static_cast<std::size_t>(c)] = place(pts[static_cast<std::size_t>(3 + from_b)]);
    s.top_a[static_cast<std::size_t>(c)] = from_a < top_count_a;
    s.top_b[static_cast<std::size_t>(c)] = from_b < top_count_b;
    s.xy_a[static_cast<std::size_t>(c)] = xy[static_cast<std::size_t>(from_a)];
    s.xy_b[static_cast<std::size_t>(c)] = xy[static_cast<std::size_t>(3 + from_b)];
  }
  s.m = m;
  s.nx = nx;
  s.ny = ny;
  s.power = power;
  s.gap = std::ldexp(static_cast<long double>(m) * std::sqrt(static_cast<long double>(nn)), power);
  const std::array<double, 3> n = {static_cast<double>(nx), static_cast<double>(ny), 1.0};
  for (int k = 0; k < 3; ++k) {
    const double v = n[static_cast<std::size_t>(axis_perm[k])] / std::sqrt(static_cast<double>(nn));
    s.unit_normal[k] = (signs >> k) & 1 ? -v : v;
  }
  s.scale = 0;
  for (const Triangle* t : {&s.a, &s.b})
    for (const Vec3& x : *t) s.scale = std::max(s.scale, x.cwiseAbs().maxCoeff());
  if (s.scale == 0) s.scale = 1;
  s.recipe = recipe.str();
  return s;
}

/// Tolerance of the checks, in units of e * S (e = 2^-53): the distance primitives promise a
/// few (docs/algorithms.md, "Exactness"); tests/core/test_triangle_distance.cpp uses the same 16.
inline constexpr double kSlabTolUlps = 16.0;

/// The exact distance between a feature of A and a feature of B given as corner sets (bit i:
/// corner i), when the construction knows it: both features on top and, where it matters, the
/// whole feature on top, so that the distance is sqrt((m |n|)^2 + d^2) with d their distance
/// within the plane; or the slab's width when the top parts meet. std::nullopt otherwise (then
/// the slab's width is only a lower bound).
inline std::optional<long double> slab_feature_distance(const SlabPair& s, unsigned corners_a,
                                                        unsigned corners_b) {
  std::array<Int2, 3> pa, pb, ta, tb;
  int na = 0, nb = 0, top_a = 0, top_b = 0;
  for (std::size_t c = 0; c < 3; ++c) {
    if (corners_a & (1u << c)) {
      pa[static_cast<std::size_t>(na++)] = s.xy_a[c];
      if (s.top_a[c]) ta[static_cast<std::size_t>(top_a++)] = s.xy_a[c];
    }
    if (corners_b & (1u << c)) {
      pb[static_cast<std::size_t>(nb++)] = s.xy_b[c];
      if (s.top_b[c]) tb[static_cast<std::size_t>(top_b++)] = s.xy_b[c];
    }
  }
  const long double gap_sq = static_cast<long double>(static_cast<Int128>(s.m) * s.m * (s.nx * s.nx + s.ny * s.ny + 1));
  if (top_a == na && top_b == nb) {
    return std::ldexp(std::sqrt(gap_sq + plane_hull_distance_sq(pa.data(), na, pb.data(), nb, s.nx, s.ny)), s.power);
  }
  if (top_a > 0 && top_b > 0 && hulls_meet(ta.data(), top_a, tb.data(), top_b)) return s.gap;
  return std::nullopt;
}

/// Every check of one pair; returns the first failure as a message ("" when all hold).
///   - triangle_distance, both argument orders: exactly 0 and Intersecting when m = 0 and the
///     top features meet, never Intersecting and never 0 otherwise (triangles_intersect
///     agrees); the exact distance where slab_feature_distance knows it, at least m |n|
///     otherwise (within the tolerance); points as far apart as the distance says, on their
///     sides of the slab.
///   - each of the 6 vertex-triangle and 9 edge-edge primitives: the same values, feature by
///     feature (a primitive may give 0 for features apart by less than rounding).
/// With `worst`, also raises *worst to the largest error against a known distance, in e*S.
inline std::string check_slab_pair(const SlabPair& s, double* worst = nullptr) {
  const double tol = kSlabTolUlps * 0x1p-53 * s.scale;
  std::ostringstream fail;
  fail.precision(17);
  auto check_value = [&](const std::string& what, double d, std::optional<long double> exact) {
    const long double error = static_cast<long double>(d) - (exact ? *exact : s.gap);
    if (exact && worst != nullptr) {
      *worst = std::max(*worst, static_cast<double>(std::fabs(error)) / (0x1p-53 * s.scale));
    }
    if (exact ? !(std::fabs(error) <= tol) : !(error >= -tol)) {
      fail << what << ": distance " << d << ", expected " << (exact ? "" : "at least ")
           << static_cast<double>(exact ? *exact : s.gap) << " (tolerance " << tol << ")";
      return false;
    }
    return true;
  };
  const std::optional<long double> whole = slab_feature_distance(s, 7u, 7u);
  // Whether the triangles touch is known exactly even where the distance is not: for m = 0,
  // exactly when the top features meet.
  const bool contact = s.m == 0 && top_features_meet(s);
  for (int order = 0; order < 2; ++order) {
    const Triangle& x = order == 0 ? s.a : s.b;
    const Triangle& y = order == 0 ? s.b : s.a;
    const char* name = order == 0 ? "triangle_distance(a, b)" : "triangle_distance(b, a)";
    const TriangleDistanceResult r = triangle_distance(x, y);
    // Its pruning skips only candidates that cannot win: bitwise the search over all 15.
    const TriangleDistanceResult all = detail::triangle_distance_unpruned(x, y);
    if (std::memcmp(&r.distance, &all.distance, sizeof r.distance) != 0 || r.point_a != all.point_a ||
        r.point_b != all.point_b || r.kind != all.kind || r.feature_a != all.feature_a ||
        r.feature_b != all.feature_b) {
      fail << name << ": distance " << r.distance << " (kind " << static_cast<int>(r.kind) << ", features "
           << int{r.feature_a} << ", " << int{r.feature_b} << ") but without pruning " << all.distance << " (kind "
           << static_cast<int>(all.kind) << ", features " << int{all.feature_a} << ", " << int{all.feature_b} << ")";
      return fail.str();
    }
    // With a caller's bound at the distance and just below it: kept exactly when within it,
    // then bitwise the same numbers.
    for (const double within : {r.distance, std::nextafter(r.distance, 0.0)}) {
      TriangleDistanceResult w;
      const bool kept = triangle_distance_within(x, nullptr, y, nullptr, within, w);
      if (kept != (r.distance <= within) ||
          (kept && (std::memcmp(&w.distance, &r.distance, sizeof r.distance) != 0 || w.kind != r.kind ||
                    w.feature_a != r.feature_a || w.feature_b != r.feature_b))) {
        fail << name << ": triangle_distance_within(" << within << ") " << (kept ? "kept" : "dropped")
             << " the pair at distance " << r.distance;
        return fail.str();
      }
    }
    const bool intersecting = r.kind == TriangleDistanceCase::Intersecting;
    if (intersecting != contact || triangles_intersect(x, y) != contact) {
      fail << name << ": reported " << (intersecting ? "" : "not ") << "intersecting, triangles_intersect "
           << triangles_intersect(x, y) << ", but the triangles " << (contact ? "touch" : "do not touch");
      return fail.str();
    }
    if (contact) {
      if (r.distance != 0) {
        fail << name << ": touching but distance " << r.distance;
        return fail.str();
      }
      continue;
    }
    if (!(r.distance > 0)) {  // 0 is for touching triangles alone
      fail << name << ": apart but distance " << r.distance;
      return fail.str();
    }
    if (!check_value(name, r.distance, whole)) return fail.str();
    // The points: as far apart as the distance, and on their sides of the slab.
    const Vec3& pa = order == 0 ? r.point_a : r.point_b;
    const Vec3& pb = order == 0 ? r.point_b : r.point_a;
    const auto along = [&](const Vec3& p) {
      long double v = 0;
      for (int k = 0; k < 3; ++k) v += static_cast<long double>(p[k]) * s.unit_normal[k];
      return v;
    };
    const long double plane_a = along(s.a[s.top_a[0] ? 0 : s.top_a[1] ? 1 : 2]);
    const long double plane_b = along(s.b[s.top_b[0] ? 0 : s.top_b[1] ? 1 : 2]);
    if (!(std::fabs((pa - pb).norm() - r.distance) <= tol) || !(along(pa) <= plane_a + tol) ||
        !(along(pb) >= plane_b - tol)) {
      fail << name << ": points (" << pa.transpose() << ") and (" << pb.transpose()
           << ") do not realise distance " << r.distance << " across the slab";
      return fail.str();
    }
  }
  // The primitives.
  for (int i = 0; i < 3; ++i) {
    const double d = std::sqrt(point_triangle_distance(s.a[static_cast<std::size_t>(i)], s.b).squared_distance);
    if (!check_value("point_triangle_distance(a" + std::to_string(i) + ", b)", d,
                     slab_feature_distance(s, 1u << i, 7u)))
      return fail.str();
  }
  for (int j = 0; j < 3; ++j) {
    const double d = std::sqrt(point_triangle_distance(s.b[static_cast<std::size_t>(j)], s.a).squared_distance);
    if (!check_value("point_triangle_distance(b" + std::to_string(j) + ", a)", d,
                     slab_feature_distance(s, 7u, 1u << j)))
      return fail.str();
  }
  for (std::size_t ea = 0; ea < 3; ++ea) {
    for (std::size_t eb = 0; eb < 3; ++eb) {
      const std::size_t ea1 = (ea + 1) % 3, eb1 = (eb + 1) % 3;
      const double d = std::sqrt(segment_segment_distance(s.a[ea], s.a[ea1], s.b[eb], s.b[eb1]).squared_distance);
      if (!check_value("segment_segment_distance(edge a" + std::to_string(ea) + ", edge b" + std::to_string(eb) + ")",
                       d, slab_feature_distance(s, (1u << ea) | (1u << ea1), (1u << eb) | (1u << eb1))))
        return fail.str();
    }
  }
  return "";
}

}  // namespace vproxq::test
