#include "core/geometry/separation_bound.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <limits>

namespace vproxq {
namespace {

constexpr double kMinAxisSquared = 0x1p-900;

/// Whether an axis w with w . w = ww proves anything: skipped below 2^-900 (underflow) and
/// when not finite (see the header).
bool usable_axis(double ww) { return ww >= kMinAxisSquared && std::isfinite(ww); }

/// gap / |w| for the projection gaps g of a and b onto w, |w| = `norm`.
double axis_gap(const ProjectionGaps& g, double norm) {
  const double gap = std::max(g.b_above_a, g.a_above_b) / norm;
  // Coordinates beyond ~2^300 can overflow a projection: such an axis proves nothing.
  return std::isfinite(gap) ? gap : -kInfinity;
}

/// The gap along site s's normal between its own triangle (projections s.lo..s.hi) and t:
/// axis_gap(projection_gaps(a, b, s.normal)) whichever of a and b the site's triangle is.
/// The two differences only trade places, and their max is the same either way: one is NaN
/// (infinities of one sign on both sides) only where the other is not finite either, and
/// axis_gap() returns -infinity for both.
double normal_gap(const SeparationSite& s, const Triangle& t) {
  if (std::isnan(s.normal_norm)) return -kInfinity;
  double lo = kInfinity, hi = -kInfinity;
  for (size_t k = 0; k < 3; ++k) {
    const double p = s.normal.dot(t[k]);
    lo = p < lo ? p : lo;
    hi = p > hi ? p : hi;
  }
  return axis_gap({lo - s.hi, s.lo - hi}, s.normal_norm);
}

}  // namespace

SeparationSite separation_site(const Triangle& t) {
  SeparationSite s;
  s.normal = (t[1] - t[0]).cross(t[2] - t[0]);
  const double ww = s.normal.squaredNorm();
  s.normal_norm = usable_axis(ww) ? std::sqrt(ww) : std::numeric_limits<double>::quiet_NaN();
  s.lo = kInfinity;
  s.hi = -kInfinity;
  for (size_t k = 0; k < 3; ++k) {
    const double p = s.normal.dot(t[k]);
    s.lo = p < s.lo ? p : s.lo;
    s.hi = p > s.hi ? p : s.hi;
  }
  s.sum = t[0] + t[1] + t[2];
  return s;
}

double separation_lower_bound(const Triangle& a, const SeparationSite& sa, const Triangle& b, const SeparationSite& sb) {
  // Centroid line: the sums are formed in corner order for each triangle, so swapping a and
  // b negates the axis exactly (and the gap, the larger of the two differences, is the same).
  const Vec3 centres = sb.sum - sa.sum;
  const double ww = centres.squaredNorm();
  const double g2 = usable_axis(ww) ? axis_gap(projection_gaps(a, b, centres), std::sqrt(ww)) : -kInfinity;
  // The larger of a's and b's normal gaps first, in an order that does not depend on which
  // triangle is a, so the result is symmetric.
  return std::max(std::max(normal_gap(sa, b), normal_gap(sb, a)), g2);
}

double separation_lower_bound(const Triangle& a, const Triangle& b) {
  return separation_lower_bound(a, separation_site(a), b, separation_site(b));
}

}  // namespace vproxq
