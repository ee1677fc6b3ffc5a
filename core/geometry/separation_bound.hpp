#pragma once
// A cheap lower bound on the distance between two triangles, from separating axes: it lets
// Stage III skip a triangle pair whose boxes are within the bound but whose triangles are
// provably farther apart, without running the exact test.
#include "core/types.hpp"

namespace vproxq {

/// Projections of the corners of a and b onto w (not divided by |w|): {smallest of b's minus
/// largest of a's, smallest of a's minus largest of b's}. Both are <= 0 when the projections
/// overlap; otherwise the positive one is their gap (divided by |w|: a lower bound on the
/// distance between the triangles).
struct ProjectionGaps {
  double b_above_a, a_above_b;
};
inline ProjectionGaps projection_gaps(const Triangle& a, const Triangle& b, const Vec3& w) {
  double a_lo = kInfinity, a_hi = -kInfinity, b_lo = kInfinity, b_hi = -kInfinity;
  for (size_t k = 0; k < 3; ++k) {
    const double pa = w.dot(a[k]), pb = w.dot(b[k]);
    a_lo = pa < a_lo ? pa : a_lo;
    a_hi = pa > a_hi ? pa : a_hi;
    b_lo = pb < b_lo ? pb : b_lo;
    b_hi = pb > b_hi ? pb : b_hi;
  }
  return {b_lo - a_hi, a_lo - b_hi};
}

/// A lower bound on the distance between the closed triangles a and b: the largest gap
/// between their projections onto three axes, a's normal, b's normal and the line through
/// their centroids (an axis of a degenerate triangle is skipped); -infinity when no axis
/// separates them. The projections are not normalised beforehand: the gap along an axis w is
/// (gap of the dot products) / |w|, so the bound holds for every w, exact normal or not.
///
/// Rounding (u = 2^-53, M = the largest |coordinate| of the 6 points; core/ is built without
/// FMA contraction): each dot product w . x is off by at most γ_3 |w|_1 M <= 3.01u sqrt(3)
/// |w| M; a gap, the difference of two of them, by 2 * 5.3u |w| M plus its own rounding
/// u |gap|; dividing by the rounded sqrt(w . w) (relative error below 3u) and rounding adds
/// 4u |gap / |w||, and |gap / |w|| <= 2 sqrt(3) M. So the result exceeds the exact distance
/// by at most 11u M + 14u M < 2^-48 M. Axes with w . w below 2^-900 are skipped, so underflow
/// does not enter; nothing overflows for coordinates below 2^200 in magnitude (the range where
/// triangle_distance is exact), and an axis whose w . w or gap is not finite is skipped.
/// Callers compare the bound with a best distance plus a slack that covers 2^-48 M and the
/// exact test's own rounding (for Stage III, rounding_slack()), so a skipped pair could not
/// have been at or below that best distance.
///
/// Symmetric: separation_lower_bound(a, b) == separation_lower_bound(b, a), bitwise.
double separation_lower_bound(const Triangle& a, const Triangle& b);

/// The part of separation_lower_bound() that depends on one triangle alone: its normal axis
/// (and the projections of its own corners onto it) and the sum of its corners. A search that
/// meets each triangle in many pairs computes it once per triangle.
struct SeparationSite {
  Vec3 normal;            ///< (t1 - t0) x (t2 - t0)
  double normal_norm;     ///< sqrt(normal . normal); NaN when the axis is skipped (see .cpp)
  double lo, hi;          ///< the smallest and largest of normal . t_k
  Vec3 sum;               ///< t0 + t1 + t2
};
SeparationSite separation_site(const Triangle& t);

/// separation_lower_bound(a, b), bitwise, from a's and b's sites (separation_site()).
double separation_lower_bound(const Triangle& a, const SeparationSite& sa, const Triangle& b, const SeparationSite& sb);

}  // namespace vproxq
