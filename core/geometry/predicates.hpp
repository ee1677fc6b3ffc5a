#pragma once
// Exact orientation predicates for double inputs (floating-point filter + exact expansion
// arithmetic fallback, after Shewchuk 1997).
//
// Both predicates return the exact sign (-1, 0, +1) of a determinant of the input doubles, as if
// evaluated in infinite precision. They are exact as long as no intermediate product overflows
// or underflows; this holds when every nonzero coordinate has magnitude in [2^-200, 2^200]
// (about 6e-61 .. 1.6e60), far beyond any mesh coordinate. Inputs must be finite.
#include "core/types.hpp"

namespace vproxq {

using Vec2 = Eigen::Matrix<double, 2, 1>;

/// Sign of det[b-a; c-a] = (b-a) x (c-a): +1 when a, b, c turn counterclockwise (c left of the
/// directed line a->b), -1 clockwise, 0 collinear (repeated points included).
int orient2d(const Vec2& a, const Vec2& b, const Vec2& c);

/// orient2d of the projections of a, b, c onto the coordinate plane that drops axis
/// `drop_axis` (0, 1 or 2); the kept axes are (drop_axis+1)%3 and (drop_axis+2)%3, in that
/// order, so the result is the sign of component `drop_axis` of (b-a) x (c-a).
int orient2d_projected(const Vec3& a, const Vec3& b, const Vec3& c, int drop_axis);

/// Sign of det[b-a; c-a; d-a] = ((b-a) x (c-a)) . (d-a): +1 when d lies on the side of the
/// plane (a, b, c) that the normal (b-a) x (c-a) points to (a, b, c counterclockwise seen from
/// d), -1 on the other side, 0 when the four points are coplanar (degenerate cases included).
/// Note: Shewchuk's orient3d uses the opposite sign.
int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d);

/// Counters of how often the exact fallback ran (for tests and statistics; thread-local).
struct PredicateCounters {
  std::uint64_t orient2d_exact = 0;
  std::uint64_t orient3d_exact = 0;
};
/// This thread's fallback counters (reset them by assigning {}).
PredicateCounters& predicate_counters();

}  // namespace vproxq
