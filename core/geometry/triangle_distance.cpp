// Triangle-triangle distance: exact intersection test, then the 15 feature pairs.
//
// Two disjoint closed triangles realise their distance at a vertex of one against the other
// (closed) triangle, or at a pair of edges, so the minimum over 6 vertex-triangle and 9
// edge-edge distances is the distance; this holds for degenerate triangles too (their
// point-triangle queries reduce to edges). Candidates are compared by squared distance, in the
// fixed order VF a0..a2, FV b0..b2, EE (0,0), (0,1), ... (2,2), a later one replacing the best
// only when strictly smaller, and the square root is taken once. The search uses the
// squared-distance cores of the primitives (each candidate is bitwise the squared distance
// point_triangle_distance or segment_segment_distance returns), shares the 18 corner-to-edge
// distances the candidates have in common, and builds points for the winner only. Everything
// is straight-line double arithmetic without heap allocation, so equal inputs give bitwise
// equal outputs.
//
// Pruning. triangle_distance() skips a candidate that provably cannot win: one whose two
// features are farther apart than r = sqrt(closest) + m, where `closest` is the smallest of the
// 18 corner-to-edge squared distances and m = 2^-30 S (S: the largest coordinate magnitude of
// the 6 corners), by either of two lower bounds of their distance:
//   - their boxes' distance (a corner's point, an edge's box, the other triangle's box); each
//     gap is one rounded difference of coordinates, so the rounded value is within a few e of
//     the exact one, relatively;
//   - the gap between their projections onto w, the difference of the triangles' centroids
//     (times 3), divided by |w|: b's feature ahead of a's along w. As in
//     separation_bound.hpp, the rounded gap over |w| exceeds the exact one by less than
//     2^-48 S (the test compares the gap with r |w|, rounded: a few e of r more).
// Every candidate's computed distance lies within 16 e S of its exact value, e = 2^-53 (the
// bound tests/core/test_triangle_distance.cpp checks for the primitives against a long-double
// twin, measured at most about 5 e S; 2^-49 S), so
//   - a skipped candidate computes to more than its exact value minus 2^-49 S, which is at
//     least the lower bound's exact value, which exceeds r less 2^-47 S (the roundings above);
//   - the winner computes to at most the exact triangle distance plus 2^-49 S (the candidate
//     that realises it computes to no more), which is at most the exact distance of the
//     corner-to-edge pair behind `closest`, itself within 2^-49 S of sqrt(closest).
// As m = 2^-30 S is far above these roundings, a skipped candidate computes to strictly more
// than the winner: it would not have replaced the best, and skipping it changes nothing. Every
// other candidate is evaluated as before, in the same order, so the result is bitwise that of
// the search over all 15 (detail::triangle_distance_unpruned(), the twin the tests compare
// it with). A triangle whose vertex candidates are all skipped is not prepared at all. On the
// pairs of the intra-object distance about 4.6 of the 15 are evaluated (docs/algorithms.md, "Exactness").
//
// A caller's bound. triangle_distance_within() uses r = within + m instead where that is
// smaller: by the same roundings, a candidate skipped for it computes to more than `within`.
// So when the result computes to at most `within`, every skipped candidate computes to more
// than the result, which is bitwise as above; otherwise the evaluated candidates compute to
// more than `within` too (or none is left), and the answer is "farther". The roundings above
// are relative to r, and stay below 2^-47 S while r is a few S (as sqrt(closest) + m is):
// `within` is used only when at most 4 S (corners within S of the origin are at most
// 2 sqrt(3) S apart, so a larger bound would skip nothing anyway). It joins the radius from
// the 18 corner-to-edge distances, which are still computed: applied before them, it skipped
// all 15 candidates of 6 in 100,000 pairs of the intra-object search (funnel), and the extra
// pass over the 15 bounds cost more than that saved.
#include "core/geometry/triangle_distance.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "core/broad_phase/aabb.hpp"
#include "core/geometry/point_triangle.hpp"
#include "core/geometry/segment_segment.hpp"
#include "core/geometry/triangle_intersection.hpp"

namespace vproxq {

namespace {

/// Index of a candidate in the documented order: VF a0..a2, FV b0..b2, EE (ea, eb) row-major.
constexpr int kFirstFaceVertex = 3;
constexpr int kFirstEdgeEdge = 6;

/// point_triangle_distance's squared distance from its plan and the corner-to-edge squared
/// distances: the least of the face candidate and the edges the plan asks for. Only the value
/// is needed, so it is a plain minimum (selects, not branches).
double point_triangle_squared(const detail::PointTrianglePlan& plan, const double (&edge_sq)[3]) {
  double best = plan.face_squared_distance;
  for (int k = 0; k < 3; ++k) {
    const bool wanted = (plan.edge_mask & (1u << k)) != 0;
    best = detail::min_value(best, detail::select(wanted, edge_sq[k], kInfinity));
  }
  return best;
}

/// Pruning margin per unit of the coordinates' magnitude (m above).
constexpr double kPruneMargin = 0x1p-30;
/// A caller's bound `within` prunes only when it is at most this many S (see the top).
constexpr double kWithinScales = 4;

/// The box of a segment's corners.
inline AABB segment_box(const Vec3& p, const Vec3& q) { return {p.cwiseMin(q), p.cwiseMax(q)}; }

}  // namespace

// The winner's points from the stand-alone primitive (its squared distance is the one the
// search found, bitwise); an intersecting pair has its common point already.
void add_closest_points(TriangleDistanceResult& r, const Triangle& a, const PreparedTriangle* pre_a,
                        const Triangle& b, const PreparedTriangle* pre_b) {
  switch (r.kind) {
    case TriangleDistanceCase::Intersecting:
      return;  // the common point is set already
    case TriangleDistanceCase::VertexFace: {
      const Vec3& p = a[static_cast<size_t>(r.feature_a)];
      r.point_a = p;
      r.point_b = (pre_b ? point_triangle_distance(p, *pre_b) : point_triangle_distance(p, b)).closest;
      return;
    }
    case TriangleDistanceCase::FaceVertex: {
      const Vec3& p = b[static_cast<size_t>(r.feature_b)];
      r.point_a = (pre_a ? point_triangle_distance(p, *pre_a) : point_triangle_distance(p, a)).closest;
      r.point_b = p;
      return;
    }
    case TriangleDistanceCase::EdgeEdge: {
      const int ea = r.feature_a, eb = r.feature_b;
      const SegmentSegmentResult e = segment_segment_distance(a[static_cast<size_t>(ea)], a[static_cast<size_t>((ea + 1) % 3)],
                                                              b[static_cast<size_t>(eb)], b[static_cast<size_t>((eb + 1) % 3)]);
      r.point_a = e.point_a;
      r.point_b = e.point_b;
      return;
    }
  }
}

namespace {

/// The squared distances of every corner of a to every edge of b (a_to_b[i][k]: corner i, edge
/// k) and of every corner of b to every edge of a (b_to_a[j][k]), each bitwise
/// detail::point_segment_core(corner, edge's first corner, edge's second corner).
///
/// With SSE2 the two are computed side by side, a_to_b[i][k] in the low lane and b_to_a[i][k]
/// in the high one, from shared differences, by the core's operations in its order (Eigen
/// sums a Vec3's dot product as (x0 y0 + x1 y1) + x2 y2; core/ has no FMA contraction):
///   - ap, the corner minus the edge's first corner: a_i - b_k and b_i - a_k, i.e. P_i - Q_k
///     with P_i = (a_i, b_i) and Q_k = (b_k, a_k);
///   - d, the edge: Q_{k+1} - Q_k, so db_k and da_k;
///   - the end's squared distance (the core's (edge's second corner - corner) squared): the
///     squares of Q_{k+1} - P_i, that is of ap at (i, k+1) negated, which rounds alike;
///   - t = max(0, min(along / dd, 1)) with the core's operand order (min_value(x, 1) is
///     minsd(1, x); max_value(0, m) is maxsd(m, 0)), then (t d - ap) squared, and the select.
inline void corner_to_edge(const Triangle& a, const Triangle& b, double (&a_to_b)[3][3], double (&b_to_a)[3][3]) {
#if defined(__SSE2__)
  __m128d p[3][3], q[3][3];  // [corner][axis]: P = (a, b), Q = (b, a)
  for (int i = 0; i < 3; ++i) {
    for (int x = 0; x < 3; ++x) {
      p[i][x] = _mm_set_pd(b[i][x], a[i][x]);
      q[i][x] = _mm_shuffle_pd(p[i][x], p[i][x], 1);
    }
  }
  auto norm2 = [](const __m128d (&v)[3]) {
    return _mm_add_pd(_mm_add_pd(_mm_mul_pd(v[0], v[0]), _mm_mul_pd(v[1], v[1])), _mm_mul_pd(v[2], v[2]));
  };
  __m128d ap[3][3][3], ap2[3][3], d[3][3], dd[3];
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) {
      for (int x = 0; x < 3; ++x) ap[i][k][x] = _mm_sub_pd(p[i][x], q[k][x]);
      ap2[i][k] = norm2(ap[i][k]);
    }
  }
  for (int k = 0; k < 3; ++k) {
    for (int x = 0; x < 3; ++x) d[k][x] = _mm_sub_pd(q[(k + 1) % 3][x], q[k][x]);
    dd[k] = norm2(d[k]);
  }
  const __m128d zero = _mm_setzero_pd(), one = _mm_set1_pd(1.0);
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) {
      const __m128d(&v)[3] = ap[i][k];
      const __m128d(&e)[3] = d[k];
      const __m128d along =
          _mm_add_pd(_mm_add_pd(_mm_mul_pd(v[0], e[0]), _mm_mul_pd(v[1], e[1])), _mm_mul_pd(v[2], e[2]));
      const __m128d t = _mm_max_pd(_mm_min_pd(one, _mm_div_pd(along, dd[k])), zero);
      const __m128d w[3] = {_mm_sub_pd(_mm_mul_pd(t, e[0]), v[0]), _mm_sub_pd(_mm_mul_pd(t, e[1]), v[1]),
                            _mm_sub_pd(_mm_mul_pd(t, e[2]), v[2])};
      const __m128d at_end = _mm_cmpeq_pd(t, one);
      const __m128d sq = _mm_or_pd(_mm_and_pd(at_end, ap2[i][(k + 1) % 3]), _mm_andnot_pd(at_end, norm2(w)));
      _mm_storel_pd(&a_to_b[i][k], sq);
      _mm_storeh_pd(&b_to_a[i][k], sq);
    }
  }
#else
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) {
      a_to_b[i][k] = detail::point_segment_core(a[i], b[k], b[(k + 1) % 3]).squared_distance;
      b_to_a[i][k] = detail::point_segment_core(b[i], a[k], a[(k + 1) % 3]).squared_distance;
    }
  }
#endif
}

/// The 15-candidate search, with or without pruning (see the top of the file); with kPoints,
/// the winner's points too. pre_a, pre_b: the triangles prepared by the caller, or null.
/// Returns false, leaving r unspecified, exactly when the result's distance exceeds `within`
/// (with pruning; without, pass infinity).
template <bool kPrune, bool kPoints>
bool search(const Triangle& a, const Triangle& b, const PreparedTriangle* pre_a, const PreparedTriangle* pre_b,
            double within, TriangleDistanceResult& r) {
  r = TriangleDistanceResult{};
  const IntersectionResult hit = triangle_intersection(a, b);
  if (hit.intersecting) {
    r.distance = 0.0;
    r.point_a = hit.point;
    r.point_b = hit.point;
    r.kind = TriangleDistanceCase::Intersecting;
    return r.distance <= within;
  }
  // What the pruning reads: the triangles' boxes and their edges' boxes, the corners'
  // projections onto w (b's centroid minus a's, times 3) and each edge's extreme one.
  double scale = 0, wnorm = 0;
  AABB box_a, box_b, edge_box_a[3], edge_box_b[3];
  double pa[3] = {0, 0, 0}, pb[3] = {0, 0, 0}, pa_max = 0, pb_min = 0, edge_hi_a[3] = {0, 0, 0},
         edge_lo_b[3] = {0, 0, 0};
  if constexpr (kPrune) {
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k)
        scale = detail::max_value(scale, detail::max_value(std::fabs(a[i][k]), std::fabs(b[i][k])));
    box_a = AABB::of(a);
    box_b = AABB::of(b);
    const Vec3 w = (b[0] + b[1] + b[2]) - (a[0] + a[1] + a[2]);
    for (int i = 0; i < 3; ++i) {
      pa[i] = w.dot(a[i]);
      pb[i] = w.dot(b[i]);
    }
    pa_max = std::max({pa[0], pa[1], pa[2]});
    pb_min = std::min({pb[0], pb[1], pb[2]});
    wnorm = std::sqrt(w.squaredNorm());
    for (int k = 0; k < 3; ++k) {
      const int k1 = (k + 1) % 3;
      edge_box_a[k] = segment_box(a[k], a[k1]);
      edge_box_b[k] = segment_box(b[k], b[k1]);
      edge_hi_a[k] = std::max(pa[k], pa[k1]);
      edge_lo_b[k] = std::min(pb[k], pb[k1]);
    }
  }
  // Candidate c is skipped when its features are more than r apart by their boxes (squared:
  // limit) or along w (wlimit = r |w|); without pruning, nothing is.
  double limit = kInfinity, wlimit = kInfinity;
  auto kept = [&](int c) {
    if constexpr (!kPrune) {
      return true;
    } else {
      double gap, box2;
      if (c < kFirstFaceVertex) {
        gap = pb_min - pa[c];
        if (gap > wlimit) return false;
        box2 = box_distance_squared({a[c], a[c]}, box_b);
      } else if (c < kFirstEdgeEdge) {
        const int j = c - kFirstFaceVertex;
        gap = pb[j] - pa_max;
        if (gap > wlimit) return false;
        box2 = box_distance_squared({b[j], b[j]}, box_a);
      } else {
        const int ea = (c - kFirstEdgeEdge) / 3, eb = (c - kFirstEdgeEdge) % 3;
        gap = edge_lo_b[eb] - edge_hi_a[ea];
        if (gap > wlimit) return false;
        box2 = box_distance_squared(edge_box_a[ea], edge_box_b[eb]);
      }
      return !(box2 > limit);
    }
  };
  // A caller's bound: used when small enough for the rounding argument (see the top).
  double r_within = kInfinity;
  if constexpr (kPrune) {
    if (within <= kWithinScales * scale) r_within = within + kPruneMargin * scale;
  }
  // Search with squared distances only. Every corner against every edge of the other triangle
  // is computed once: these 18 values serve both the vertex-triangle candidates (their edge
  // parts) and the edge-edge candidates (their boundary parts).
  double a_to_b[3][3];  // [corner of a][edge of b]
  double b_to_a[3][3];  // [corner of b][edge of a]
  corner_to_edge(a, b, a_to_b, b_to_a);
  double best = kInfinity;
  int winner = -1;
  auto offer = [&](double squared, int candidate) {
    const bool better = squared < best;  // strictly: ties keep the earlier candidate
    winner = better ? candidate : winner;
    best = detail::select(better, squared, best);
  };
  if constexpr (kPrune) {
    double closest = kInfinity;
    for (int i = 0; i < 3; ++i)
      for (int k = 0; k < 3; ++k)
        closest = detail::min_value(closest, detail::min_value(a_to_b[i][k], b_to_a[i][k]));
    const double r = std::min(std::sqrt(closest) + kPruneMargin * scale, r_within);
    limit = r * r;
    wlimit = r * wnorm;
  }
  // Each triangle is prepared when a vertex candidate against it is evaluated first (unless
  // the caller prepared it: prepare_triangle() is deterministic, so that is the same).
  PreparedTriangle prepared_a, prepared_b;
  auto prepared = [](const Triangle& t, PreparedTriangle& p, const PreparedTriangle*& have) -> const PreparedTriangle& {
    if (have == nullptr) {
      p = prepare_triangle(t);
      have = &p;
    }
    return *have;
  };
  for (int i = 0; i < 3; ++i) {
    if (!kept(i)) continue;
    offer(point_triangle_squared(detail::plan_point_triangle(a[i], prepared(b, prepared_b, pre_b)), a_to_b[i]), i);
  }
  for (int j = 0; j < 3; ++j) {
    const int c = kFirstFaceVertex + j;
    if (!kept(c)) continue;
    offer(point_triangle_squared(detail::plan_point_triangle(b[j], prepared(a, prepared_a, pre_a)), b_to_a[j]), c);
  }
  for (int ea = 0; ea < 3; ++ea) {
    const int ea1 = (ea + 1) % 3;
    for (int eb = 0; eb < 3; ++eb) {
      const int c = kFirstEdgeEdge + 3 * ea + eb;
      if (!kept(c)) continue;
      const int eb1 = (eb + 1) % 3;
      const detail::SegmentInteriorCore interior = detail::segment_interior_core(a[ea], a[ea1], b[eb], b[eb1]);
      // The boundary's value (which endpoint wins does not matter for the value).
      const double from_a = detail::min_value(a_to_b[ea][eb], a_to_b[ea1][eb]);
      const double from_b = detail::min_value(b_to_a[eb][ea], b_to_a[eb1][ea]);
      const double boundary = detail::min_value(from_a, from_b);
      offer(detail::select(interior.found, interior.squared_distance, boundary), c);
    }
  }
  if (winner < 0) {
    // Every candidate skipped: by `within` (the result is farther), or for NaN input, which
    // is outside the contract.
    if (r_within < kInfinity) return false;
    r.distance = std::numeric_limits<double>::quiet_NaN();
    return true;
  }
  if (winner < kFirstFaceVertex) {
    r.kind = TriangleDistanceCase::VertexFace;
    r.feature_a = static_cast<std::int8_t>(winner);
  } else if (winner < kFirstEdgeEdge) {
    r.kind = TriangleDistanceCase::FaceVertex;
    r.feature_b = static_cast<std::int8_t>(winner - kFirstFaceVertex);
  } else {
    r.kind = TriangleDistanceCase::EdgeEdge;
    r.feature_a = static_cast<std::int8_t>((winner - kFirstEdgeEdge) / 3);
    r.feature_b = static_cast<std::int8_t>((winner - kFirstEdgeEdge) % 3);
  }
  r.distance = std::sqrt(best);
  // Triangles that do not touch can still compute as 0 apart: a gap below about one ulp of
  // their coordinates (a vertex within rounding of the other's plane, say) rounds away in the
  // coordinate differences. 0 stays the answer of touching pairs alone (decided exactly
  // above), so such a pair gets the smallest positive double instead: as accurate as 0, and a
  // touching pair beats it in every search and tie-break.
  if (r.distance == 0.0) r.distance = std::numeric_limits<double>::denorm_min();
  if (!(r.distance <= within)) return false;
  // The winner was evaluated, so the triangle its vertex case needs is prepared.
  if constexpr (kPoints) add_closest_points(r, a, pre_a, b, pre_b);
  return true;
}

}  // namespace

TriangleDistanceResult triangle_distance(const Triangle& a, const Triangle& b) {
  TriangleDistanceResult r;
  search<true, true>(a, b, nullptr, nullptr, kInfinity, r);
  return r;
}

bool triangle_distance_within(const Triangle& a, const PreparedTriangle* pa, const Triangle& b,
                              const PreparedTriangle* pb, double within, TriangleDistanceResult& r) {
  return search<true, false>(a, b, pa, pb, within, r);
}

namespace detail {
TriangleDistanceResult triangle_distance_unpruned(const Triangle& a, const Triangle& b) {
  TriangleDistanceResult r;
  search<false, true>(a, b, nullptr, nullptr, kInfinity, r);
  return r;
}
}  // namespace detail

}  // namespace vproxq
