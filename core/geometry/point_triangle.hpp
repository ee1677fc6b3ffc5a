#pragma once
// Point-triangle distance with the closest point and the feature (vertex, edge, face) it lies on.
#include <cmath>

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
  Vec3 normal;         ///< (c1-c0) x (c2-c0), computed accurately (relative error a few e) at
                       ///< the corner opposite the longest edge (point_triangle.cpp)
  double normal_sq;    ///< |normal|^2; 0 for a flat (degenerate) triangle: the edges decide
  double side_bound[3];  ///< side k's rounding bound per unit of |p - corner k|_1 (plan below)
};

/// Computes the PreparedTriangle of t.
PreparedTriangle prepare_triangle(const Triangle& t);

/// The part of a PreparedTriangle that costs more than its corners' differences (the accurate
/// normal most): what a search that meets each triangle in many pairs keeps per triangle,
/// 56 bytes instead of 200.
struct PreparedTriangleParts {
  Vec3 normal;
  double normal_sq;
  double side_bound[3];
};
inline PreparedTriangleParts parts_of(const PreparedTriangle& p) {
  return {p.normal, p.normal_sq, {p.side_bound[0], p.side_bound[1], p.side_bound[2]}};
}
/// prepare_triangle(t), bitwise, from parts_of(prepare_triangle(t)): the corners and edges are
/// computed as prepare_triangle() computes them.
inline PreparedTriangle prepared_from_parts(const Triangle& t, const PreparedTriangleParts& parts) {
  PreparedTriangle p;
  p.corners = t;
  for (int k = 0; k < 3; ++k) p.edges[k] = t[static_cast<size_t>((k + 1) % 3)] - t[static_cast<size_t>(k)];
  p.normal = parts.normal;
  p.normal_sq = parts.normal_sq;
  for (int k = 0; k < 3; ++k) p.side_bound[k] = parts.side_bound[k];
  return p;
}

/// Distance from p to the closed triangle t (any shape).
///
/// When the orthogonal projection of p onto the triangle's plane falls inside the triangle,
/// the closest point is that projection (region Face); otherwise it is on the edges whose
/// inner side the projection is not on. The plane's normal is computed accurately for every
/// shape, and "inside" is decided with a rounding filter whose doubtful cases are recomputed
/// accurately, so needles, caps and points just beside an edge are all within a few e*S (see
/// point_triangle.cpp). A flat triangle (collinear or repeated corners, or sin < 4e) is the
/// union of its edges: the result is the distance to the nearest edge, region Vertex or Edge.
/// Ties go to Face, then Edge0..2.
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

/// Where the orthogonal projection of p onto t's plane lies, decided without the rounding
/// doubt of plan_point_triangle's sides (cold path): inside (the Face candidate counts) or
/// outside, with the edges to compare (bit k: edge k).
struct FaceDecision {
  bool inside;
  std::uint8_t edge_mask;
};

/// Decides what plan_point_triangle's rounded sides could not (point_triangle.cpp).
/// `projection` is the computed orthogonal projection of p, `height` its distance from p.
FaceDecision decide_face(const Vec3& p, const PreparedTriangle& t, const Vec3& projection, double height);

/// Branch-free on the data but for the rare doubtful sides (the face candidate is always
/// computed, and discarded when the projection is outside); it branches on the triangle's
/// shape.
inline PointTrianglePlan plan_point_triangle(const Vec3& p, const PreparedTriangle& t) {
  constexpr std::uint8_t kAllEdges = 0b111;
  if (!(t.normal_sq > 0.0)) {  // flat: the union of the edges
    return {kInfinity, Vec3::Zero(), kAllEdges};
  }
  // The face candidate: the orthogonal projection onto the plane (accurate to a few e |p - c0|
  // with the accurate normal).
  const Vec3 ap = p - t.corners[0];
  const Vec3 offset = -(ap.dot(t.normal) / t.normal_sq) * t.normal;  // projection - p
  const double face_sq = offset.squaredNorm();
  // side[k] = det(edge k, p - corner k, n): >= 0 when p projects onto the inner side of edge
  // k; it is |n| times twice the area of (corner k, corner k+1, projection of p), i.e. the
  // unnormalised barycentric coordinate of corner k+2. Its sign is certain when |side[k]|
  // exceeds the rounding bound side_bound[k] |p - corner k|_1; otherwise decide_face() settles
  // the question. A wrong sign would be no small matter: beyond the tip of a needle the
  // projection lies within rounding of both long edges' lines while far from the triangle,
  // and calling it inside put such points up to 0.13 too close (a needle 2 long with a tip
  // angle of 1e-12).
  const Vec3 bp = p - t.corners[1];
  const Vec3 cp = p - t.corners[2];
  const double side0 = t.edges[0].cross(ap).dot(t.normal);
  const double side1 = t.edges[1].cross(bp).dot(t.normal);
  const double side2 = t.edges[2].cross(cp).dot(t.normal);
  const bool certain0 = std::fabs(side0) > t.side_bound[0] * ap.cwiseAbs().sum();
  const bool certain1 = std::fabs(side1) > t.side_bound[1] * bp.cwiseAbs().sum();
  const bool certain2 = std::fabs(side2) > t.side_bound[2] * cp.cwiseAbs().sum();
  const bool certain = certain0 & certain1 & certain2;
  if (!certain) {
    const FaceDecision d = decide_face(p, t, p + offset, std::sqrt(face_sq));
    return {select(d.inside, face_sq, kInfinity), p + offset, d.edge_mask};
  }
  const bool inside = (side0 > 0.0) & (side1 > 0.0) & (side2 > 0.0);
  // Outside, the closest point lies on an edge whose side is negative (one or two edges; with
  // two, their shared corner is on both).
  const auto outside_mask =
      static_cast<std::uint8_t>((side0 < 0.0 ? 1 : 0) | (side1 < 0.0 ? 2 : 0) | (side2 < 0.0 ? 4 : 0));
  return {select(inside, face_sq, kInfinity), p + offset, inside ? std::uint8_t{0} : outside_mask};
}
}  // namespace detail

}  // namespace vproxq
