#include "core/geometry/separation_bound.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>

namespace vproxq {
namespace {

constexpr double kMinAxisSquared = 0x1p-900;

/// The gap between the projections of a and b onto w, divided by |w| (see the header).
/// Swapping a and b, or negating w, gives bitwise the same value.
double axis_gap(const Triangle& a, const Triangle& b, const Vec3& w) {
  const double ww = w.squaredNorm();
  if (!(ww >= kMinAxisSquared) || !std::isfinite(ww)) return -kInfinity;
  const ProjectionGaps g = projection_gaps(a, b, w);
  const double gap = std::max(g.b_above_a, g.a_above_b) / std::sqrt(ww);
  // Coordinates beyond ~2^300 can overflow a projection: such an axis proves nothing.
  return std::isfinite(gap) ? gap : -kInfinity;
}

}  // namespace

double separation_lower_bound(const Triangle& a, const Triangle& b) {
  // Centroid line: the sums are formed in corner order for each triangle, so swapping a and
  // b negates the axis exactly.
  const Vec3 centres = (b[0] + b[1] + b[2]) - (a[0] + a[1] + a[2]);
  const double g0 = axis_gap(a, b, (a[1] - a[0]).cross(a[2] - a[0]));
  const double g1 = axis_gap(a, b, (b[1] - b[0]).cross(b[2] - b[0]));
  // The larger of a's and b's normal gaps first, in an order that does not depend on which
  // triangle is a, so the result is symmetric.
  return std::max(std::max(g0, g1), axis_gap(a, b, centres));
}

}  // namespace vproxq
