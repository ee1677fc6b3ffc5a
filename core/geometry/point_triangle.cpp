#include "core/geometry/point_triangle.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace vproxq {
namespace {

/// Smallest sin of the largest angle for which a triangle has a plane: the accurate normal's
/// error is about e|n| + 4e^2|e1||e2|, a direction error of about e + 4e^2/sin, which at
/// sin = 4e is 2e. Flatter triangles are treated as the union of their edges; that changes the
/// distance by at most half the triangle's width, |e1| sin / 2 < 2e|e1|.
constexpr double kFlatSin = 4.0 * 0x1p-53;

/// The rounding bound of a side in plan_point_triangle, per |edge k| |n| |p - corner k|_2 (and
/// so also per the larger |p - corner k|_1). side = (a x b) . n with a = fl(corner k+1 -
/// corner k), b = fl(p - corner k): each component of a and b carries a relative error e,
/// each product and difference of the cross product another e, so component i of a x b is off
/// by at most 4e (|a_j b_k| + |a_k b_j|); against n (taken as exact: the side is defined by
/// it) that sums to 4e sqrt(2) |a| |b| |n| (Cauchy-Schwarz), and the dot product adds 3e
/// |a x b| |n| <= 3e |a| |b| |n|: 8.66e in all, to first order. 10e leaves room for the
/// rounding of the bound itself.
constexpr double kSideError = 10.0 * 0x1p-53;

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
  // At the corner j1 opposite the longest edge (the largest angle), with the orientation of
  // (c1-c0) x (c2-c0). A plain cross product there would be off in direction by about
  // 4e / sin(angle): fine for most triangles, but projecting along it puts the face candidate
  // off by that angle times the distance along the plane, and caps (largest angle near 180
  // degrees) have sin down to 4e.
  const int j = (longest + 1) % 3;
  const int j1 = (longest + 2) % 3;
  pt.normal = accurate_normal(t[j1], t[(j1 + 1) % 3], t[(j1 + 2) % 3]);
  pt.normal_sq = pt.normal.squaredNorm();
  const double edges_sq = len_sq[j] * len_sq[j1];  // |e1|^2 |e2|^2
  if (!(pt.normal_sq >= kFlatSin * kFlatSin * edges_sq)) {
    pt.normal_sq = 0.0;  // flat: the union of the edges
  }
  const double normal_norm = std::sqrt(pt.normal_sq);
  for (int k = 0; k < 3; ++k) {
    pt.side_bound[k] = kSideError * std::sqrt(len_sq[k]) * normal_norm;
  }
  return pt;
}

namespace detail {

FaceDecision decide_face(const Vec3& p, const PreparedTriangle& t, const Vec3& projection, double height) {
  constexpr double e = 0x1p-53;
  constexpr std::uint8_t kAllEdges = 0b111;
  // 1. The sides again, each cross product (corner k+1 - corner k) x (p - corner k) from exact
  // coordinate differences and compensated products (as accurate_normal: a relative error of a
  // few e per component). What is left of a side's error is about 3e |cross| |n| from the dot
  // product, 2e |cross| |n| from the cross product's rounding and 2e |cross| |n| from the
  // normal's direction (the truth is the exact plane's): 8e |cross| |n| bounds it. In
  // distance units (per |edge| |n|) that is 8e times the distance from p to the edge's line:
  // next to nothing for p near the plane, about 8e h for p at height h above it.
  double side[3], doubt[3];
  bool inside = true, outside = false;
  std::uint8_t negative = 0;
  for (int k = 0; k < 3; ++k) {
    const Vec3 cross = accurate_normal(t.corners[k], t.corners[(k + 1) % 3], p);
    side[k] = cross.dot(t.normal);
    const double bound = 8.0 * e * cross.norm() * std::sqrt(t.normal_sq);
    inside &= side[k] > bound;
    outside |= side[k] < -bound;
    negative |= static_cast<std::uint8_t>(side[k] < 0.0 ? 1u << k : 0u);
    doubt[k] = std::fabs(side[k]) > bound ? 0.0 : 2.0 * bound;  // |exact side| <= doubt
  }
  if (inside) return {true, 0};
  if (outside) return {false, negative};
  // 2. Still in doubt, with no side surely negative: a projection inside the triangle is
  // within (doubt of side k) / (|edge k| |n|) of the line of each doubtful edge k, so within
  // that of the boundary. A projection farther than that (plus the rounding of the computed
  // projection and of the distances to it) from every edge is outside. This is what keeps a
  // point past the tip of a thin needle, whose projection lies within the doubt of both long
  // edges' lines, from being taken for inside. Otherwise the face candidate counts: if the
  // projection is in fact outside, it is within that margin of the triangle, so the
  // distance is off by at most the margin (a few e |p| near the plane, and only to second
  // order, margin^2 / 2h, at height h).
  double margin = 0.0;
  for (int k = 0; k < 3; ++k) {
    margin = std::max(margin, doubt[k] / (std::sqrt(t.edges[k].squaredNorm()) * std::sqrt(t.normal_sq)));
  }
  double boundary_sq = kInfinity;
  for (int k = 0; k < 3; ++k) {
    boundary_sq = std::min(boundary_sq,
                           point_segment_core(projection, t.corners[k], t.corners[(k + 1) % 3]).squared_distance);
  }
  // The projection's position: the normal's direction (2e h) and the rounding of p + offset
  // (e per coordinate); the distances to the edges: a few e of the coordinates' magnitude.
  const double magnitude = std::max({p.cwiseAbs().maxCoeff(), projection.cwiseAbs().maxCoeff(),
                                     t.corners[0].cwiseAbs().maxCoeff(), t.corners[1].cwiseAbs().maxCoeff(),
                                     t.corners[2].cwiseAbs().maxCoeff()});
  margin += 2.0 * e * height + 8.0 * e * magnitude;
  if (std::sqrt(boundary_sq) > margin) return {false, kAllEdges};
  return {true, 0};
}

}  // namespace detail

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
