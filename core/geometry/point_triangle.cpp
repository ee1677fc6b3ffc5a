#include "core/geometry/point_triangle.hpp"

#include <Eigen/Geometry>
#include <cmath>

namespace vproxq {
namespace {

/// Smallest |n|^2 / L^4 (n the normal below, L the longest edge; |n| is twice the area) for which
/// the plain normal and the convex-combination face candidate are used: twice the area at least
/// 1e-3 L^2. The normal is the cross product of the two edges at the corner opposite the longest
/// edge (the largest angle), computed in double: rounding of the edge differences and products
/// gives it an absolute error of about 4e|e1||e2| (e = 2^-53), a direction error of about
/// 4e/sin(angle) radians, below 5e-13 rad here. The face candidate is built from barycentric
/// coordinates side_k / sum, where each side_k has an absolute error of about e |edge| |p - corner|
/// |n| and sum is about |n|^2: the point is off by at most about e L^2 |p - corner| / |n| along the
/// triangle (a crude bound: for 3.4 million needles with |n| / L^2 between 1e-3 and 1e-1, queried
/// from points just off them, the distance was within 0.003 e*S). Two shapes fail this and take the
/// other path: caps (nearly collinear corners, largest angle near 180 degrees) and needles (one
/// edge short beside two long ones: |n| ~ L times the short edge). Needles used to pass the test,
/// made on the largest angle alone: for needles 2 long in the plane, queried from points just off
/// them, the distance was off by up to 8e-13 with a short edge below 1e-3, 1e-8 below 1e-5 and
/// 1.2 below 1e-13 (now within 2.4 e*S in the test PointTriangle.NeedlesMatchTheirKnownDistance).
/// On the other path the normal is recomputed accurately (see accurate_normal) and the face
/// candidate is the orthogonal projection onto that plane, whose distance is accurate to about
/// e |p - corner| for any shape; the projection is also compared with all three edges. The threshold
/// only moves work between the two paths; both are accurate on their side of it.
constexpr double kWellShapedAreaSq = 1e-6;

/// Smallest sin of the largest angle for which a cap's accurate normal is trusted: its error is
/// about e|n| + 4e^2|e1||e2|, i.e. a direction error of about e + 4e^2/sin; at sin = 64e that
/// is still ~1.06e. Flatter triangles are treated as the union of their edges; that changes the
/// distance by at most the triangle's width, |e1| sin < 64e|e1|.
constexpr double kFlatSin = 64.0 * 0x1p-53;

PointTriangleRegion vertex_region(int k) { return static_cast<PointTriangleRegion>(k); }
PointTriangleRegion edge_region(int k) { return static_cast<PointTriangleRegion>(3 + k); }

/// a*b - c*d with a relative error of about 2e (Kahan's algorithm with a fused multiply-add).
double difference_of_products(double a, double b, double c, double d) {
  const double cd = c * d;
  const double cd_error = std::fma(-c, d, cd);  // cd - c*d, exact
  return std::fma(a, b, -cd) + cd_error;
}

/// hi + lo == a - b exactly, with hi = fl(a - b) (Knuth's two-sum of a and -b).
void exact_difference(double a, double b, double& hi, double& lo) {
  hi = a - b;
  const double b_virtual = hi - a;  // approximately -b
  const double a_virtual = hi - b_virtual;
  lo = (a - a_virtual) + (-b - b_virtual);
}

/// (v1 - v0) x (v2 - v0) with a relative error of a few e, also for nearly collinear corners.
/// The edge differences are split exactly into hi + lo; hi x hi is evaluated with
/// difference_of_products, the first-order lo terms in plain double, lo x lo (~e^2) is dropped.
Vec3 accurate_normal(const Vec3& v0, const Vec3& v1, const Vec3& v2) {
  double hi1[3], lo1[3], hi2[3], lo2[3];
  for (int k = 0; k < 3; ++k) {
    exact_difference(v1[k], v0[k], hi1[k], lo1[k]);
    exact_difference(v2[k], v0[k], hi2[k], lo2[k]);
  }
  Vec3 n;
  for (int k = 0; k < 3; ++k) {
    const int i = (k + 1) % 3;
    const int j = (k + 2) % 3;
    const double main = difference_of_products(hi1[i], hi2[j], hi1[j], hi2[i]);
    const double left = hi1[i] * lo2[j] + lo1[i] * hi2[j];
    const double right = hi1[j] * lo2[i] + lo1[j] * hi2[i];
    n[k] = main + (left - right);
  }
  return n;
}

}  // namespace

PreparedTriangle prepare_triangle(const Triangle& t) {
  PreparedTriangle pt;
  pt.corners = t;
  double len_sq[3];
  for (int k = 0; k < 3; ++k) {
    pt.edges[k] = t[(k + 1) % 3] - t[k];
    len_sq[k] = pt.edges[k].squaredNorm();
  }
  int longest = 0;
  if (len_sq[1] > len_sq[longest]) longest = 1;
  if (len_sq[2] > len_sq[longest]) longest = 2;
  // The two edges meeting at the corner opposite the longest edge: its angle is the largest,
  // so for needles (one short edge) the cross product is well conditioned.
  const int j = (longest + 1) % 3;
  const int j1 = (longest + 2) % 3;
  pt.normal = pt.edges[j].cross(pt.edges[j1]);
  pt.normal_sq = pt.normal.squaredNorm();
  const double edges_sq = len_sq[j] * len_sq[j1];  // |e1|^2 |e2|^2
  pt.well_shaped = pt.normal_sq >= kWellShapedAreaSq * (len_sq[longest] * len_sq[longest]) && pt.normal_sq > 0.0;
  if (!pt.well_shaped) {
    // At the same corner j1 (opposite the longest edge), with the same orientation.
    pt.normal = accurate_normal(t[j1], t[(j1 + 1) % 3], t[(j1 + 2) % 3]);
    pt.normal_sq = pt.normal.squaredNorm();
    if (!(pt.normal_sq >= kFlatSin * kFlatSin * edges_sq)) {
      pt.normal_sq = 0.0;  // flat: the union of the edges
    }
  }
  return pt;
}

PointTriangleResult point_triangle_distance(const Vec3& p, const Triangle& t) {
  return point_triangle_distance(p, prepare_triangle(t));
}

PointTriangleResult point_triangle_distance(const Vec3& p, const PreparedTriangle& t) {
  const detail::PointTrianglePlan plan = detail::plan_point_triangle(p, t);
  PointTriangleResult best;
  if (plan.face_squared_distance < kInfinity) {
    best.squared_distance = plan.face_squared_distance;
    best.closest = plan.face_closest;
    best.region = PointTriangleRegion::Face;
  }
  for (int k = 0; k < 3; ++k) {
    if ((plan.edge_mask & (1u << k)) == 0) {
      continue;
    }
    const int k1 = (k + 1) % 3;
    const PointSegmentResult e = point_segment_distance(p, t.corners[k], t.corners[k1]);
    if (e.squared_distance < best.squared_distance) {
      best.squared_distance = e.squared_distance;
      best.closest = e.closest;
      best.region = e.t == 0.0 ? vertex_region(k) : e.t == 1.0 ? vertex_region(k1) : edge_region(k);
    }
  }
  return best;
}

}  // namespace vproxq
