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

/// The 15-candidate search, with or without pruning (see the top of the file); with kPoints,
/// the winner's points too. pre_a, pre_b: the triangles prepared by the caller, or null.
template <bool kPrune, bool kPoints>
TriangleDistanceResult search(const Triangle& a, const Triangle& b, const PreparedTriangle* pre_a,
                              const PreparedTriangle* pre_b) {
  TriangleDistanceResult r;
  const IntersectionResult hit = triangle_intersection(a, b);
  if (hit.intersecting) {
    r.distance = 0.0;
    r.point_a = hit.point;
    r.point_b = hit.point;
    r.kind = TriangleDistanceCase::Intersecting;
    return r;
  }
  // Search with squared distances only. Every corner against every edge of the other triangle
  // is computed once: these 18 values serve both the vertex-triangle candidates (their edge
  // parts) and the edge-edge candidates (their boundary parts).
  double a_to_b[3][3];  // [corner of a][edge of b]
  double b_to_a[3][3];  // [corner of b][edge of a]
  for (int i = 0; i < 3; ++i) {
    for (int k = 0; k < 3; ++k) {
      a_to_b[i][k] = detail::point_segment_core(a[i], b[k], b[(k + 1) % 3]).squared_distance;
      b_to_a[i][k] = detail::point_segment_core(b[i], a[k], a[(k + 1) % 3]).squared_distance;
    }
  }
  double best = kInfinity;
  int winner = -1;
  auto offer = [&](double squared, int candidate) {
    const bool better = squared < best;  // strictly: ties keep the earlier candidate
    winner = better ? candidate : winner;
    best = detail::select(better, squared, best);
  };
  // Pruning: a candidate whose features' boxes are more than r apart (squared: limit) is
  // skipped; without it, limit stays infinite and nothing is.
  double limit = kInfinity, wlimit = kInfinity;
  AABB box_a, box_b;
  double pa[3] = {0, 0, 0}, pb[3] = {0, 0, 0}, pa_max = 0, pb_min = 0;
  if constexpr (kPrune) {
    double closest = kInfinity, scale = 0;
    for (int i = 0; i < 3; ++i) {
      for (int k = 0; k < 3; ++k) {
        closest = detail::min_value(closest, detail::min_value(a_to_b[i][k], b_to_a[i][k]));
        scale = detail::max_value(scale, detail::max_value(std::fabs(a[i][k]), std::fabs(b[i][k])));
      }
    }
    const double r = std::sqrt(closest) + kPruneMargin * scale;
    limit = r * r;
    box_a = AABB::of(a);
    box_b = AABB::of(b);
    const Vec3 w = (b[0] + b[1] + b[2]) - (a[0] + a[1] + a[2]);
    for (int i = 0; i < 3; ++i) {
      pa[i] = w.dot(a[i]);
      pb[i] = w.dot(b[i]);
    }
    pa_max = std::max({pa[0], pa[1], pa[2]});
    pb_min = std::min({pb[0], pb[1], pb[2]});
    wlimit = r * std::sqrt(w.squaredNorm());
  }
  auto skipped = [&](const AABB& p, const AABB& q) { return kPrune && box_distance_squared(p, q) > limit; };
  auto apart = [&](double a_hi, double b_lo) { return kPrune && b_lo - a_hi > wlimit; };
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
    if (apart(pa[i], pb_min) || skipped({a[i], a[i]}, box_b)) continue;
    offer(point_triangle_squared(detail::plan_point_triangle(a[i], prepared(b, prepared_b, pre_b)), a_to_b[i]), i);
  }
  for (int j = 0; j < 3; ++j) {
    if (apart(pa_max, pb[j]) || skipped({b[j], b[j]}, box_a)) continue;
    offer(point_triangle_squared(detail::plan_point_triangle(b[j], prepared(a, prepared_a, pre_a)), b_to_a[j]),
          kFirstFaceVertex + j);
  }
  for (int ea = 0; ea < 3; ++ea) {
    const int ea1 = (ea + 1) % 3;
    for (int eb = 0; eb < 3; ++eb) {
      const int eb1 = (eb + 1) % 3;
      if (apart(std::max(pa[ea], pa[ea1]), std::min(pb[eb], pb[eb1])) ||
          skipped(segment_box(a[ea], a[ea1]), segment_box(b[eb], b[eb1])))
        continue;
      const detail::SegmentInteriorCore interior =
          detail::segment_interior_core(a[ea], a[ea1], b[eb], b[eb1]);
      // The boundary's value (which endpoint wins does not matter for the value).
      const double from_a = detail::min_value(a_to_b[ea][eb], a_to_b[ea1][eb]);
      const double from_b = detail::min_value(b_to_a[eb][ea], b_to_a[eb1][ea]);
      const double boundary = detail::min_value(from_a, from_b);
      offer(detail::select(interior.found, interior.squared_distance, boundary),
            kFirstEdgeEdge + 3 * ea + eb);
    }
  }
  if (winner < 0) {  // only for NaN input, which is outside the contract
    r.distance = std::numeric_limits<double>::quiet_NaN();
    return r;
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
  // The winner was evaluated, so the triangle its vertex case needs is prepared.
  if constexpr (kPoints) add_closest_points(r, a, pre_a, b, pre_b);
  r.distance = std::sqrt(best);
  // Triangles that do not touch can still compute as 0 apart: a gap below about one ulp of
  // their coordinates (a vertex within rounding of the other's plane, say) rounds away in the
  // coordinate differences. 0 stays the answer of touching pairs alone (decided exactly
  // above), so such a pair gets the smallest positive double instead: as accurate as 0, and a
  // touching pair beats it in every search and tie-break.
  if (r.distance == 0.0) r.distance = std::numeric_limits<double>::denorm_min();
  return r;
}

}  // namespace

TriangleDistanceResult triangle_distance(const Triangle& a, const Triangle& b) {
  return search<true, true>(a, b, nullptr, nullptr);
}

TriangleDistanceResult triangle_distance_without_points(const Triangle& a, const PreparedTriangle* pa,
                                                        const Triangle& b, const PreparedTriangle* pb) {
  return search<true, false>(a, b, pa, pb);
}

namespace detail {
TriangleDistanceResult triangle_distance_unpruned(const Triangle& a, const Triangle& b) {
  return search<false, true>(a, b, nullptr, nullptr);
}
}  // namespace detail

}  // namespace vproxq
