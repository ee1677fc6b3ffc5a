#pragma once
// Exact intersection tests of closed segments and triangles (orientation predicates only).
//
// Decisions are exact for any double input (see predicates.hpp for the range): touching
// counts as intersecting, and degenerate inputs are handled as the point sets they are (a
// zero-area triangle is the union of its edges; a segment may be a single point). The
// intersection points returned alongside are approximate (double arithmetic).
//
// triangles_intersect(a, b), declared in triangle_distance.hpp, is defined with these.
#include "core/types.hpp"

namespace vproxq {

/// Outcome of an exact intersection test with one common point (approximate) when it hits.
struct IntersectionResult {
  bool intersecting = false;
  Vec3 point = Vec3::Zero();  ///< a common point, rounded; meaningful only when intersecting
};

/// True when the three corners are collinear (zero area; repeated corners included). Exact.
bool triangle_is_degenerate(const Triangle& t);

/// Whether the closed triangles a and b share a point (exact), with one such point.
/// Two closed triangles meet iff an edge of one meets the other triangle; the test first
/// rejects with bounding boxes and with "all corners of one strictly on one side of the
/// other's plane", then tests the edges that reach the other triangle's plane.
IntersectionResult triangle_intersection(const Triangle& a, const Triangle& b);

/// Whether the closed segment [p0, p1] meets the closed triangle t (exact), with one common
/// point.
IntersectionResult segment_triangle_intersection(const Vec3& p0, const Vec3& p1,
                                                 const Triangle& t);

/// Whether the closed segments [p0, p1] and [q0, q1] share a point (exact), with one such point.
IntersectionResult segment_segment_intersection(const Vec3& p0, const Vec3& p1, const Vec3& q0,
                                                const Vec3& q1);

}  // namespace vproxq
