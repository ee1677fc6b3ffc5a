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
#include "core/geometry/triangle_distance.hpp"

#include <cmath>
#include <limits>

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

}  // namespace

TriangleDistanceResult triangle_distance(const Triangle& a, const Triangle& b) {
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
  const PreparedTriangle prepared_b = prepare_triangle(b);
  for (int i = 0; i < 3; ++i) {
    offer(point_triangle_squared(detail::plan_point_triangle(a[i], prepared_b), a_to_b[i]), i);
  }
  const PreparedTriangle prepared_a = prepare_triangle(a);
  for (int j = 0; j < 3; ++j) {
    offer(point_triangle_squared(detail::plan_point_triangle(b[j], prepared_a), b_to_a[j]),
          kFirstFaceVertex + j);
  }
  for (int ea = 0; ea < 3; ++ea) {
    const int ea1 = (ea + 1) % 3;
    for (int eb = 0; eb < 3; ++eb) {
      const int eb1 = (eb + 1) % 3;
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
  // Points of the winner only, from the stand-alone primitive (its squared distance is the
  // one found above, bitwise).
  if (winner < kFirstFaceVertex) {
    r.point_a = a[winner];
    r.point_b = point_triangle_distance(a[winner], prepared_b).closest;
    r.kind = TriangleDistanceCase::VertexFace;
    r.feature_a = static_cast<std::int8_t>(winner);
  } else if (winner < kFirstEdgeEdge) {
    const int j = winner - kFirstFaceVertex;
    r.point_a = point_triangle_distance(b[j], prepared_a).closest;
    r.point_b = b[j];
    r.kind = TriangleDistanceCase::FaceVertex;
    r.feature_b = static_cast<std::int8_t>(j);
  } else {
    const int ea = (winner - kFirstEdgeEdge) / 3;
    const int eb = (winner - kFirstEdgeEdge) % 3;
    const SegmentSegmentResult e =
        segment_segment_distance(a[ea], a[(ea + 1) % 3], b[eb], b[(eb + 1) % 3]);
    r.point_a = e.point_a;
    r.point_b = e.point_b;
    r.kind = TriangleDistanceCase::EdgeEdge;
    r.feature_a = static_cast<std::int8_t>(ea);
    r.feature_b = static_cast<std::int8_t>(eb);
  }
  r.distance = std::sqrt(best);
  // Triangles that do not touch can still compute as 0 apart: a gap below about one ulp of
  // their coordinates (a vertex within rounding of the other's plane, say) rounds away in the
  // coordinate differences. 0 stays the answer of touching pairs alone (decided exactly
  // above), so such a pair gets the smallest positive double instead: as accurate as 0, and a
  // touching pair beats it in every search and tie-break.
  if (r.distance == 0.0) r.distance = std::numeric_limits<double>::denorm_min();
  return r;
}

}  // namespace vproxq
