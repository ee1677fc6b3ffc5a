#pragma once
// Exact-as-double triangle–triangle distance with closest points and the winning feature case.
#include "core/geometry/point_triangle.hpp"
#include "core/types.hpp"

#include <utility>

namespace vproxq {

/// Which feature pair realises the distance between triangles A and B.
enum class TriangleDistanceCase : std::uint8_t {
  Intersecting,  ///< the closed triangles share a point; distance is exactly 0
  VertexFace,    ///< a vertex of A (feature_a) against the closed triangle B
  FaceVertex,    ///< the closed triangle A against a vertex of B (feature_b)
  EdgeEdge,      ///< edge feature_a of A against edge feature_b of B
};

/// Result of triangle_distance(). Edge k of a triangle joins corner k and corner (k+1)%3.
struct TriangleDistanceResult {
  double distance = kInfinity;
  Vec3 point_a = Vec3::Zero();  ///< closest point on A
  Vec3 point_b = Vec3::Zero();  ///< closest point on B (== point_a when intersecting)
  TriangleDistanceCase kind = TriangleDistanceCase::Intersecting;
  std::int8_t feature_a = -1;  ///< corner (VertexFace) or edge (EdgeEdge) of A, else -1
  std::int8_t feature_b = -1;  ///< corner (FaceVertex) or edge (EdgeEdge) of B, else -1
};

/// Distance between the closed triangles a and b (any shape, degenerate ones included).
/// Intersection is decided with exact orientation predicates, so touching or crossing
/// triangles give exactly 0, and only they do: triangles apart by less than rounding, whose
/// computed distance is 0, get the smallest positive double (denorm_min) instead. Otherwise
/// the distance is the minimum over the 6 vertex–face and 9 edge–edge feature pairs, ties
/// going to the first in that order.
///
/// Details (core/geometry/triangle_distance.cpp): the order is VF a0, a1, a2, FV b0, b1, b2,
/// then EE (feature_a, feature_b) row-major; squared distances are compared and the square root
/// taken once; each candidate's value is bitwise that of point_triangle_distance() or
/// segment_segment_distance() (the winner's square root: that distance, but denorm_min for 0),
/// and the reported points are theirs. Distances are accurate to a few ulps of the largest
/// coordinate (they are computed from coordinate differences); points are rounded to their
/// coordinates' grid. For intersecting triangles point_a == point_b is one common point,
/// computed approximately (within a few ulps of both triangles). Feature pairs that provably
/// cannot win are skipped, which changes no bit of the result. Deterministic: equal inputs
/// give bitwise equal results. Inputs must be finite; exactness of the intersection decision
/// holds for coordinates of magnitude in [2^-200, 2^200] or zero (predicates.hpp).
TriangleDistanceResult triangle_distance(const Triangle& a, const Triangle& b);

/// triangle_distance() in two steps, for callers that keep few of the pairs they evaluate,
/// and only those within a bound `within` (>= 0, not NaN; infinity: no bound): true when
/// triangle_distance(a, b).distance <= within, with r set to its distance, case and features,
/// the points left at zero (but for an intersecting pair, whose common point is set); else
/// false, r unspecified. add_closest_points() then fills in the points of a result that is
/// kept. Feature pairs farther apart than `within` are skipped too, so far pairs cost less (a
/// search that keeps the nearest pair passes its best so far). `pa` and `pb` are
/// prepare_triangle(a) and prepare_triangle(b) when the caller has them (each triangle of a
/// search met in many pairs is prepared once), else null. Together, bitwise the numbers of
/// triangle_distance(a, b).
bool triangle_distance_within(const Triangle& a, const PreparedTriangle* pa, const Triangle& b,
                              const PreparedTriangle* pb, double within, TriangleDistanceResult& r);
/// Fills in the points of r, from a true triangle_distance_within(a, pa, b, pb, ...).
void add_closest_points(TriangleDistanceResult& r, const Triangle& a, const PreparedTriangle* pa,
                        const Triangle& b, const PreparedTriangle* pb);

namespace detail {
/// triangle_distance() without its pruning: all 15 candidates are evaluated. Bitwise the same
/// result (triangle_distance.cpp says why); the twin the tests compare triangle_distance with.
TriangleDistanceResult triangle_distance_unpruned(const Triangle& a, const Triangle& b);
}  // namespace detail

/// r seen from the other triangle's side: points, features and the vertex–face case swapped.
inline TriangleDistanceResult swapped(TriangleDistanceResult r) {
  std::swap(r.point_a, r.point_b);
  std::swap(r.feature_a, r.feature_b);
  if (r.kind == TriangleDistanceCase::VertexFace)
    r.kind = TriangleDistanceCase::FaceVertex;
  else if (r.kind == TriangleDistanceCase::FaceVertex)
    r.kind = TriangleDistanceCase::VertexFace;
  return r;
}

/// triangle_distance(a, b) when `a_first`, else triangle_distance(b, a) seen from a's side
/// (points, features and the vertex–face case swapped). Callers that must get bitwise the
/// same numbers for (a, b) and (b, a) pass a fixed order, e.g. "lower id first".
inline TriangleDistanceResult triangle_distance_ordered(const Triangle& a, const Triangle& b,
                                                        bool a_first) {
  return a_first ? triangle_distance(a, b) : swapped(triangle_distance(b, a));
}

/// True when the closed triangles a and b share at least one point (exact predicates). A
/// degenerate triangle is the union of its edges. Defined in triangle_intersection.cpp, which
/// also offers the common point (triangle_intersection()).
bool triangles_intersect(const Triangle& a, const Triangle& b);

}  // namespace vproxq
