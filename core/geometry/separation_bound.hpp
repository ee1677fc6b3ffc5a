#pragma once
// A cheap lower bound on the distance between two triangles, from separating axes: it lets
// Stage III skip a triangle pair whose boxes are within the bound but whose triangles are
// provably farther apart, without running the exact test.
#include "core/types.hpp"

namespace vproxq {

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
/// triangle_distance is exact), and an axis whose w . w or gap is not finite is skipped. Callers compare the bound with a best
/// distance plus a slack that covers 2^-48 M and the exact test's own rounding (for Stage III,
/// rounding_slack()), so a skipped pair could not have been at or below that best distance.
///
/// Symmetric: separation_lower_bound(a, b) == separation_lower_bound(b, a), bitwise.
double separation_lower_bound(const Triangle& a, const Triangle& b);

}  // namespace vproxq
