#pragma once
// Point-triangle distance with the closest point and the feature (vertex, edge, face) it lies on.
#include "core/geometry/segment_segment.hpp"
#include "core/types.hpp"

namespace vproxq {

/// Feature of the triangle that holds the closest point. Edge k joins corner k and (k+1)%3.
enum class PointTriangleRegion : std::uint8_t {
  Vertex0,
  Vertex1,
  Vertex2,
  Edge0,
  Edge1,
  Edge2,
  Face,  ///< the relative interior of a non-degenerate triangle
};

/// Closest point of a triangle to a point.
struct PointTriangleResult {
  double squared_distance = kInfinity;  ///< from coordinate differences (accurate far from 0)
  Vec3 closest = Vec3::Zero();          ///< on the closed triangle (up to coordinate rounding)
  PointTriangleRegion region = PointTriangleRegion::Face;
};

/// Per-triangle quantities shared by all point queries against one triangle.
struct PreparedTriangle {
  Triangle corners;
  Vec3 edges[3];       ///< edges[k] = corner (k+1)%3 - corner k
  Vec3 normal;         ///< (c1-c0) x (c2-c0), at the corner opposite the longest edge;
                       ///< recomputed accurately when not well_shaped (point_triangle.cpp)
  double normal_sq;    ///< |normal|^2; 0 for a flat (degenerate) triangle: the edges decide
  bool well_shaped;    ///< |normal| >= 1e-3 (longest edge)^2: neither a cap nor a needle
};

/// Computes the PreparedTriangle of t.
PreparedTriangle prepare_triangle(const Triangle& t);

/// Distance from p to the closed triangle t (any shape).
///
/// When the projection of p falls inside a well-shaped triangle, the closest point is that
/// projection (region Face), built as a convex combination of the corners; otherwise it is on
/// the edges whose inner side p is not on. A cap or a needle (twice the area below 1e-3 times
/// the longest edge squared: nearly collinear corners, or one edge much shorter than the other
/// two) uses an accurately computed normal and compares the projection with all three edges. A flat
/// triangle (collinear or repeated corners, or sin < 64e) is the union of its edges: the result
/// is the distance to the nearest edge, region Vertex or Edge. Ties go to Face, then Edge0..2.
PointTriangleResult point_triangle_distance(const Vec3& p, const Triangle& t);

/// Same as point_triangle_distance(p, t) for t = prepared.corners, bitwise.
PointTriangleResult point_triangle_distance(const Vec3& p, const PreparedTriangle& prepared);

namespace detail {
// Squared-distance-only core of point_triangle_distance, inline so that triangle_distance can
// run its 15-candidate search without building points. point_triangle_distance is built on
// it, so the squared distance is bitwise the same.

/// The face test of p against a prepared triangle, and what remains to compare after it.
struct PointTrianglePlan {
  double face_squared_distance;  ///< Face candidate; kInfinity when there is none
  Vec3 face_closest;             ///< the Face candidate's point (when there is one)
  std::uint8_t edge_mask;        ///< bit k: edge k (corners k, k+1) must be compared too
};

/// Branch-free on the data (the face candidate is always computed, and discarded when the
/// projection is outside; for p in the plane of a flat configuration that may divide by zero,
/// harmlessly); it branches only on the triangle's shape.
inline PointTrianglePlan plan_point_triangle(const Vec3& p, const PreparedTriangle& t) {
  constexpr std::uint8_t kAllEdges = 0b111;
  if (!(t.normal_sq > 0.0)) {  // flat: the union of the edges
    return {kInfinity, Vec3::Zero(), kAllEdges};
  }
  // side[k] = det(edge k, p - corner k, n): >= 0 when p projects onto the inner side of edge
  // k; it is |n| times twice the area of (corner k, corner k+1, projection of p), i.e. the
  // unnormalised barycentric coordinate of corner k+2.
  const Vec3 ap = p - t.corners[0];
  const double side0 = t.edges[0].cross(ap).dot(t.normal);
  const double side1 = t.edges[1].cross(p - t.corners[1]).dot(t.normal);
  const double side2 = t.edges[2].cross(p - t.corners[2]).dot(t.normal);
  const double sum = side0 + side1 + side2;
  const bool inside = (side0 >= 0.0) & (side1 >= 0.0) & (side2 >= 0.0) & (sum > 0.0);
  if (t.well_shaped) {
    // Closest = c0 + b1 (c1 - c0) + b2 (c2 - c0), a convex combination of the corners.
    const double bary1 = side2 / sum;  // corner 1 is opposite edge 2
    const double bary2 = side0 / sum;  // corner 2 is opposite edge 0
    const Vec3 from_c0 = bary1 * t.edges[0] - bary2 * t.edges[2];
    const double face_sq = (from_c0 - ap).squaredNorm();
    // Outside: the closest point lies on an edge whose side is negative (one or two edges;
    // with two, their shared corner is on both).
    const auto outside_mask = static_cast<std::uint8_t>(
        (side0 < 0.0 ? 1 : 0) | (side1 < 0.0 ? 2 : 0) | (side2 < 0.0 ? 4 : 0));
    const std::uint8_t mask = inside ? std::uint8_t{0} : outside_mask != 0 ? outside_mask : kAllEdges;
    return {select(inside, face_sq, kInfinity), t.corners[0] + from_c0, mask};
  }
  // A cap (nearly collinear corners) with an accurately computed normal: the orthogonal
  // projection onto the plane, also compared with all three edges.
  const Vec3 offset = -(ap.dot(t.normal) / t.normal_sq) * t.normal;  // closest - p
  return {select(inside, offset.squaredNorm(), kInfinity), p + offset, kAllEdges};
}
}  // namespace detail

}  // namespace vproxq
