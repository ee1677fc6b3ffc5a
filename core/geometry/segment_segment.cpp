#include "core/geometry/segment_segment.hpp"

namespace vproxq {

PointSegmentResult point_segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const detail::PointSegmentCore core = detail::point_segment_core(p, a, b);
  PointSegmentResult r;
  r.squared_distance = core.squared_distance;
  r.t = core.t;
  r.closest = core.at_end ? b : Vec3(a + core.t * (b - a));
  return r;
}

SegmentSegmentResult segment_segment_distance(const Vec3& p0, const Vec3& p1, const Vec3& q0,
                                              const Vec3& q1) {
  SegmentSegmentResult r;
  const detail::SegmentInteriorCore interior = detail::segment_interior_core(p0, p1, q0, q1);
  if (interior.found) {
    r.squared_distance = interior.squared_distance;
    r.s = interior.s;
    r.t = interior.t;
    r.point_a = p0 + interior.s * (p1 - p0);
    r.point_b = q0 + interior.t * (q1 - q0);
    r.kind = SegmentSegmentCase::Interior;
    return r;
  }
  // Boundary of the parameter square, in tie order: an endpoint against the other segment.
  const PointSegmentResult candidates[4] = {
      point_segment_distance(p0, q0, q1), point_segment_distance(p1, q0, q1),
      point_segment_distance(q0, p0, p1), point_segment_distance(q1, p0, p1)};
  const double squared[4] = {candidates[0].squared_distance, candidates[1].squared_distance,
                             candidates[2].squared_distance, candidates[3].squared_distance};
  const int best = detail::best_boundary_index(squared);
  const PointSegmentResult& c = candidates[best];
  r.squared_distance = c.squared_distance;
  r.kind = static_cast<SegmentSegmentCase>(1 + best);
  const bool endpoint_of_a = best < 2;  // StartA, EndA: an endpoint of A against B
  const bool at_end = best % 2 == 1;     // EndA, EndB
  if (endpoint_of_a) {
    r.point_a = at_end ? p1 : p0;
    r.point_b = c.closest;
    r.s = at_end ? 1.0 : 0.0;
    r.t = c.t;
  } else {
    r.point_a = c.closest;
    r.point_b = at_end ? q1 : q0;
    r.s = c.t;
    r.t = at_end ? 1.0 : 0.0;
  }
  return r;
}

}  // namespace vproxq
