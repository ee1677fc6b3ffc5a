// Exact segment/triangle intersection tests built on orient3d and orient2d.
//
// Decision logic (all predicates exact):
//  * segment-segment in 3D: the segments can only meet if their four endpoints are coplanar;
//    coplanar segments meet iff their projections meet on all three coordinate planes (one of
//    those projections is injective on a plane containing all four points, and a projection
//    never separates a common point).
//  * segment-segment in 2D: the classic test: a proper crossing (strictly opposite sides both
//    ways), or an endpoint collinear with and inside the bounding box of the other segment.
//  * segment vs non-degenerate triangle: endpoints strictly on one side of the plane -> no;
//    both on the plane -> 2D test in a coordinate projection where the triangle keeps nonzero
//    area; otherwise the segment meets the plane in one point X, and X is in the closed triangle
//    iff orient3d(p0, p1, t_k, t_k+1), k = 0..2, do not take both strict signs (each equals
//    sign((p1-p0).n) times the orientation of (X, t_k, t_k+1) in the plane, and the three
//    orientations sum to the triangle's nonzero area).
//  * a degenerate triangle is the union of its three edges.
#include "core/geometry/triangle_intersection.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

#include "core/geometry/point_triangle.hpp"
#include "core/geometry/predicates.hpp"
#include "core/geometry/segment_segment.hpp"
#include "core/geometry/triangle_distance.hpp"

namespace vproxq {
namespace {

IntersectionResult hit_at(const Vec3& point) { return IntersectionResult{true, point}; }
IntersectionResult miss() { return IntersectionResult{}; }

/// One common point of two segments known to intersect (approximate: their closest points).
Vec3 common_point(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1) {
  return segment_segment_distance(p0, p1, q0, q1).point_a;
}

/// Whether x lies in the bounding box of a and b on the two axes kept by the projection.
bool in_projected_box(const Vec3& x, const Vec3& a, const Vec3& b, int drop_axis) {
  for (int axis : {(drop_axis + 1) % 3, (drop_axis + 2) % 3}) {
    if (x[axis] < std::min(a[axis], b[axis]) || x[axis] > std::max(a[axis], b[axis])) {
      return false;
    }
  }
  return true;
}

/// Whether the projections of the closed segments [p0, p1] and [q0, q1] meet (exact).
bool segments_meet_projected(const Vec3& p0, const Vec3& p1, const Vec3& q0, const Vec3& q1,
                             int drop_axis) {
  const int o_q0 = orient2d_projected(p0, p1, q0, drop_axis);
  const int o_q1 = orient2d_projected(p0, p1, q1, drop_axis);
  const int o_p0 = orient2d_projected(q0, q1, p0, drop_axis);
  const int o_p1 = orient2d_projected(q0, q1, p1, drop_axis);
  if (o_q0 * o_q1 < 0 && o_p0 * o_p1 < 0) {
    return true;
  }
  return (o_q0 == 0 && in_projected_box(q0, p0, p1, drop_axis)) ||
         (o_q1 == 0 && in_projected_box(q1, p0, p1, drop_axis)) ||
         (o_p0 == 0 && in_projected_box(p0, q0, q1, drop_axis)) ||
         (o_p1 == 0 && in_projected_box(p1, q0, q1, drop_axis));
}

/// Whether two point sets' bounding boxes are strictly apart on some axis (exact).
template <std::size_t N, std::size_t M>
bool boxes_apart(const std::array<const Vec3*, N>& a, const std::array<const Vec3*, M>& b) {
  for (int axis = 0; axis < 3; ++axis) {
    double a_min = (*a[0])[axis];
    double a_max = a_min;
    for (const Vec3* p : a) {
      a_min = std::min(a_min, (*p)[axis]);
      a_max = std::max(a_max, (*p)[axis]);
    }
    double b_min = (*b[0])[axis];
    double b_max = b_min;
    for (const Vec3* p : b) {
      b_min = std::min(b_min, (*p)[axis]);
      b_max = std::max(b_max, (*p)[axis]);
    }
    if (a_max < b_min || b_max < a_min) {
      return true;
    }
  }
  return false;
}

/// A coordinate axis whose dropping keeps the non-degenerate triangle t non-degenerate (exact);
/// the axis of the largest normal component is tried first.
int projection_axis(const Triangle& t) {
  const Vec3 n = (t[1] - t[0]).cross(t[2] - t[0]);
  int first = 0;
  if (std::fabs(n[1]) > std::fabs(n[first])) first = 1;
  if (std::fabs(n[2]) > std::fabs(n[first])) first = 2;
  for (int i = 0; i < 3; ++i) {
    const int axis = (first + i) % 3;
    if (orient2d_projected(t[0], t[1], t[2], axis) != 0) {
      return axis;
    }
  }
  return first;  // unreachable for a non-degenerate triangle
}

/// Whether x (coplanar with t) lies in the closed non-degenerate triangle t, tested in the
/// projection that drops `axis` (where t has nonzero orientation `t_orientation`).
bool point_in_projected_triangle(const Vec3& x, const Triangle& t, int axis, int t_orientation) {
  for (int k = 0; k < 3; ++k) {
    if (orient2d_projected(t[k], t[(k + 1) % 3], x, axis) * t_orientation < 0) {
      return false;
    }
  }
  return true;
}

/// Approximate point where the segment [p0, p1], known (exactly) to cross the plane of the
/// non-degenerate triangle t inside t, meets it.
///
/// The plain formula p0 + h0/(h0-h1) (p1-p0), with h the heights over the plane, is ill
/// conditioned when the segment grazes the plane: its error along the segment grows like
/// 1/angle and can carry the point out of the triangle. Instead: the parameters whose points
/// project into t form an interval (three linear inequalities, one per edge), which contains
/// the exact crossing; the height formula is clamped to it. The result is on the segment, over
/// the triangle, and as close to the plane as the computed heights can tell, so it is within a
/// few roundings of both sets whatever the angle — as long as the interval's signs are right,
/// which rounding can break when the segment runs along an edge line of t
/// (segment_triangle_point() guards against that).
Vec3 crossing_point(const Vec3& p0, const Vec3& p1, const Triangle& t) {
  // The prepared normal is computed accurately (relative error a few e), caps included.
  const Vec3 n = prepare_triangle(t).normal;
  double lo = 0.0;
  double hi = 1.0;
  for (int k = 0; k < 3; ++k) {
    const Vec3 edge = t[(k + 1) % 3] - t[k];
    const Vec3 inward = n.cross(edge);  // in-plane, pointing into the triangle
    const double s0 = (p0 - t[k]).dot(inward);
    const double s1 = (p1 - t[k]).dot(inward);
    if (s0 < 0.0 && s1 >= 0.0) {
      lo = std::max(lo, s0 / (s0 - s1));
    } else if (s1 < 0.0 && s0 >= 0.0) {
      hi = std::min(hi, s0 / (s0 - s1));
    }
  }
  if (lo > hi) {  // rounding made the interval empty: it is tiny, take its middle
    lo = hi = 0.5 * (lo + hi);
  }
  const double h0 = (p0 - t[0]).dot(n);
  const double h1 = (p1 - t[0]).dot(n);
  const double along = std::clamp(h0 != h1 ? h0 / (h0 - h1) : 0.5, lo, hi);
  return p0 + along * (p1 - p0);
}

/// A common point of the segment [p0, p1] and the non-degenerate triangle t, known (exactly)
/// to meet where the segment crosses t's plane: crossing_point(), unless a point of the segment
/// nearest to one of t's edges is nearer to t. The interval crossing_point() clamps to comes
/// from signs that rounding can flip when the segment's projection runs along an edge line of
/// t (a segment touching t's edge, edge on edge): then it can clamp to an end of the segment
/// most of a triangle away (an audit found 8.7e-4 off on triangles of size 1e-3). Where the
/// segment touches t's boundary, the nearest points to the edges are the contact.
Vec3 segment_triangle_point(const Vec3& p0, const Vec3& p1, const Triangle& t) {
  const PreparedTriangle prepared = prepare_triangle(t);
  Vec3 best = crossing_point(p0, p1, t);
  double best_squared = point_triangle_distance(best, prepared).squared_distance;
  for (int k = 0; k < 3; ++k) {
    const SegmentSegmentResult e = segment_segment_distance(p0, p1, t[k], t[(k + 1) % 3]);
    if (e.squared_distance < best_squared) {
      best_squared = e.squared_distance;
      best = e.point_a;
    }
  }
  return best;
}

/// Segment [p0, p1] vs the union of the edges of (degenerate) triangle t.
IntersectionResult segment_vs_edges(const Vec3& p0, const Vec3& p1, const Triangle& t) {
  for (int k = 0; k < 3; ++k) {
    const IntersectionResult r = segment_segment_intersection(p0, p1, t[k], t[(k + 1) % 3]);
    if (r.intersecting) {
      return r;
    }
  }
  return miss();
}

/// Segment [p0, p1] vs the closed non-degenerate triangle t, given the exact sides
/// side0 = orient3d(t0, t1, t2, p0) and side1 = orient3d(t0, t1, t2, p1).
/// `axis` is a lazily computed projection_axis(t) (-1 until needed).
IntersectionResult segment_vs_solid(const Vec3& p0, const Vec3& p1, int side0, int side1,
                                    const Triangle& t, int& axis) {
  if (side0 * side1 > 0) {
    return miss();
  }
  if (side0 == 0 && side1 == 0) {  // coplanar: 2D test
    if (axis < 0) {
      axis = projection_axis(t);
    }
    const int t_orientation = orient2d_projected(t[0], t[1], t[2], axis);
    if (point_in_projected_triangle(p0, t, axis, t_orientation)) {
      return hit_at(p0);
    }
    if (point_in_projected_triangle(p1, t, axis, t_orientation)) {
      return hit_at(p1);
    }
    for (int k = 0; k < 3; ++k) {
      const Vec3& e0 = t[k];
      const Vec3& e1 = t[(k + 1) % 3];
      if (segments_meet_projected(p0, p1, e0, e1, axis)) {
        return hit_at(common_point(p0, p1, e0, e1));
      }
    }
    return miss();
  }
  // The segment meets the plane in exactly one point X: is X inside?
  const int s0 = orient3d(p0, p1, t[0], t[1]);
  const int s1 = orient3d(p0, p1, t[1], t[2]);
  const int s2 = orient3d(p0, p1, t[2], t[0]);
  const bool some_positive = s0 > 0 || s1 > 0 || s2 > 0;
  const bool some_negative = s0 < 0 || s1 < 0 || s2 < 0;
  if (some_positive && some_negative) {
    return miss();
  }
  if (side0 == 0) {
    return hit_at(p0);
  }
  if (side1 == 0) {
    return hit_at(p1);
  }
  return hit_at(segment_triangle_point(p0, p1, t));
}

}  // namespace

bool triangle_is_degenerate(const Triangle& t) {
  for (int axis = 0; axis < 3; ++axis) {
    if (orient2d_projected(t[0], t[1], t[2], axis) != 0) {
      return false;
    }
  }
  return true;
}

IntersectionResult segment_segment_intersection(const Vec3& p0, const Vec3& p1, const Vec3& q0,
                                                const Vec3& q1) {
  if (boxes_apart<2, 2>({&p0, &p1}, {&q0, &q1})) {
    return miss();
  }
  if (orient3d(p0, p1, q0, q1) != 0) {
    return miss();
  }
  for (int axis = 0; axis < 3; ++axis) {
    if (!segments_meet_projected(p0, p1, q0, q1, axis)) {
      return miss();
    }
  }
  return hit_at(common_point(p0, p1, q0, q1));
}

IntersectionResult segment_triangle_intersection(const Vec3& p0, const Vec3& p1,
                                                 const Triangle& t) {
  if (boxes_apart<2, 3>({&p0, &p1}, {&t[0], &t[1], &t[2]})) {
    return miss();
  }
  if (triangle_is_degenerate(t)) {
    return segment_vs_edges(p0, p1, t);
  }
  int axis = -1;
  return segment_vs_solid(p0, p1, orient3d(t[0], t[1], t[2], p0), orient3d(t[0], t[1], t[2], p1),
                          t, axis);
}

IntersectionResult triangle_intersection(const Triangle& a, const Triangle& b) {
  if (boxes_apart<3, 3>({&a[0], &a[1], &a[2]}, {&b[0], &b[1], &b[2]})) {
    return miss();
  }
  // side_b[j]: corner j of b against the plane of a; side_a[i]: corner i of a against b's.
  int side_b[3];
  for (int j = 0; j < 3; ++j) {
    side_b[j] = orient3d(a[0], a[1], a[2], b[j]);
  }
  if (side_b[0] == side_b[1] && side_b[1] == side_b[2] && side_b[0] != 0) {
    return miss();
  }
  int side_a[3];
  for (int i = 0; i < 3; ++i) {
    side_a[i] = orient3d(b[0], b[1], b[2], a[i]);
  }
  if (side_a[0] == side_a[1] && side_a[1] == side_a[2] && side_a[0] != 0) {
    return miss();
  }
  // A degenerate triangle has every point on its "plane" (all signs zero); test it exactly
  // only then. A degenerate triangle is the union of its edges, so its edges against the
  // other triangle decide.
  const bool a_flat = side_b[0] == 0 && side_b[1] == 0 && side_b[2] == 0 &&
                      triangle_is_degenerate(a);
  const bool b_flat = side_a[0] == 0 && side_a[1] == 0 && side_a[2] == 0 &&
                      triangle_is_degenerate(b);
  int axis_a = -1;
  int axis_b = -1;
  if (a_flat || !b_flat) {
    for (int i = 0; i < 3; ++i) {
      const Vec3& p0 = a[i];
      const Vec3& p1 = a[(i + 1) % 3];
      const IntersectionResult r = b_flat ? segment_vs_edges(p0, p1, b)
                                          : segment_vs_solid(p0, p1, side_a[i],
                                                             side_a[(i + 1) % 3], b, axis_b);
      if (r.intersecting) {
        return r;
      }
    }
    if (a_flat) {
      return miss();
    }
  }
  // a is solid here; b is solid, or degenerate (then its edges alone decide).
  for (int j = 0; j < 3; ++j) {
    const IntersectionResult r =
        segment_vs_solid(b[j], b[(j + 1) % 3], side_b[j], side_b[(j + 1) % 3], a, axis_a);
    if (r.intersecting) {
      return r;
    }
  }
  return miss();
}

bool triangles_intersect(const Triangle& a, const Triangle& b) {
  return triangle_intersection(a, b).intersecting;
}

}  // namespace vproxq
