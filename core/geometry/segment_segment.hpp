#pragma once
// Point-segment and segment-segment distance with closest points.
//
// Squared distances are computed from coordinate differences, not from the rounded closest
// points, so they stay accurate far from the origin; the closest points themselves carry the
// rounding of their coordinates (about one ulp of their magnitude).
#include <Eigen/Geometry>
#if defined(__SSE2__)
#include <emmintrin.h>
#endif

#include "core/types.hpp"

namespace vproxq {

/// Closest point of a segment [a, b] to a point.
struct PointSegmentResult {
  double squared_distance = kInfinity;
  Vec3 closest = Vec3::Zero();  ///< on the segment; exactly a when t == 0, exactly b when t == 1
  double t = 0.0;               ///< closest = a + t (b - a), t in [0, 1]
};

/// Distance from p to the closed segment [a, b]. A zero-length segment (a == b) is the point a.
PointSegmentResult point_segment_distance(const Vec3& p, const Vec3& a, const Vec3& b);

/// Which part of the parameter square [0,1]^2 realised a segment-segment distance.
enum class SegmentSegmentCase : std::uint8_t {
  Interior,  ///< interior critical point of the two lines (s and t from the line solution)
  StartA,    ///< endpoint p0 of segment A against segment B (s = 0)
  EndA,      ///< endpoint p1 of segment A against segment B (s = 1)
  StartB,    ///< endpoint q0 of segment B against segment A (t = 0)
  EndB,      ///< endpoint q1 of segment B against segment A (t = 1)
};

/// Closest points of two segments A = [p0, p1] and B = [q0, q1].
struct SegmentSegmentResult {
  double squared_distance = kInfinity;
  Vec3 point_a = Vec3::Zero();  ///< p0 + s (p1 - p0)
  Vec3 point_b = Vec3::Zero();  ///< q0 + t (q1 - q0)
  double s = 0.0;
  double t = 0.0;
  SegmentSegmentCase kind = SegmentSegmentCase::Interior;
};

/// Distance between the closed segments [p0, p1] and [q0, q1]; either may have zero length.
///
/// The minimum of the convex |A(s) - B(t)|^2 over [0,1]^2 is either the critical point of the
/// two lines, when that lies inside the square, or on the square's boundary, i.e. the best of
/// the four endpoint-to-segment distances (ties: StartA, EndA, StartB, EndB). The line solution
/// uses the cross product n = dA x dB (its denominator |n|^2 has relative error ~e/sin(angle),
/// where a*e - b^2 would have ~e/sin^2), and t is then re-optimised for the computed s, so for
/// nearly parallel segments the result stays within a few e*(length + offset) of the true
/// distance. Exactly parallel or degenerate segments (n == 0) go to the boundary directly.
SegmentSegmentResult segment_segment_distance(const Vec3& p0, const Vec3& p1, const Vec3& q0,
                                              const Vec3& q1);

namespace detail {
/// Branch-free cond ? if_true : if_false, min and max for doubles. In triangle_distance the
/// conditions are data dependent and unpredictable, and a mispredicted branch costs more than
/// computing both values; GCC 12 compiles both the ternary and std::min/max on doubles into
/// branches there, so SSE2 mask arithmetic is spelled out (portable fallback otherwise).
/// min_value(NaN, x) is NaN, max_value(x, NaN) is x, as for b < a ? b : a and a < b ? b : a.
#if defined(__SSE2__)
inline double select(bool cond, double if_true, double if_false) {
  const __m128d mask = _mm_castsi128_pd(_mm_set1_epi64x(-static_cast<long long>(cond)));
  return _mm_cvtsd_f64(_mm_or_pd(_mm_and_pd(mask, _mm_set_sd(if_true)),
                                 _mm_andnot_pd(mask, _mm_set_sd(if_false))));
}
inline double min_value(double a, double b) {
  return _mm_cvtsd_f64(_mm_min_sd(_mm_set_sd(b), _mm_set_sd(a)));  // b < a ? b : a
}
inline double max_value(double a, double b) {
  return _mm_cvtsd_f64(_mm_max_sd(_mm_set_sd(b), _mm_set_sd(a)));  // b > a ? b : a
}
#else
inline double select(bool cond, double if_true, double if_false) {
  const double options[2] = {if_false, if_true};
  return options[cond ? 1 : 0];
}
inline double min_value(double a, double b) { return select(b < a, b, a); }
inline double max_value(double a, double b) { return select(a < b, b, a); }
#endif

// Squared-distance-only cores of the functions above, inline so that triangle_distance can
// run its 15-candidate search without building points. The public functions are built on
// them, so a core's squared distance is bitwise the public function's.

/// point_segment_distance without the closest point.
struct PointSegmentCore {
  double squared_distance;
  double t;     ///< clamped parameter in [0, 1]
  bool at_end;  ///< t == 1: the closest point is exactly b
};

inline PointSegmentCore point_segment_core(const Vec3& p, const Vec3& a, const Vec3& b) {
  // Branch-free (both outcomes computed, then selected): in triangle_distance the cases are
  // about equally likely and a mispredicted branch costs more than the extra arithmetic.
  const Vec3 d = b - a;
  const Vec3 ap = p - a;
  const double dd = d.squaredNorm();
  const double along = ap.dot(d);
  // t = clamp(along / dd, 0, 1). A zero-length segment gives 0/0 = NaN, which the comparisons
  // inside min/max turn into t = 0.
  const double t = max_value(0.0, min_value(along / dd, 1.0));
  const bool at_end = t == 1.0;
  // closest - p from differences: -ap at t = 0 and b - p at t = 1, so a corner shared by two
  // segments gets bitwise the same distance from both.
  const double sq_end = (b - p).squaredNorm();
  const double sq_along = (t * d - ap).squaredNorm();
  return {select(at_end, sq_end, sq_along), t, at_end};
}

/// The interior critical point of segment_segment_distance.
struct SegmentInteriorCore {
  bool found;  ///< the critical point lies in [0,1]^2 (then it is the answer)
  double squared_distance;  ///< meaningful only when found
  double s;
  double t;
};

inline SegmentInteriorCore segment_interior_core(const Vec3& p0, const Vec3& p1, const Vec3& q0,
                                                 const Vec3& q1) {
  // Branch-free: everything is computed, then `found` says whether it counts. For parallel or
  // degenerate segments (n == 0) the divisions give NaN or inf (harmless: IEEE default, no
  // traps) and `found` is false.
  const Vec3 da = p1 - p0;
  const Vec3 db = q1 - q0;
  const Vec3 n = da.cross(db);
  const double nn = n.squaredNorm();
  // Lines p0 + s da and q0 + t db: (s da - t db - w) is parallel to n, hence
  // s = ((w x db) . n) / |n|^2. Then t minimises the distance for that s.
  const Vec3 w = q0 - p0;
  const double s = w.cross(db).dot(n) / nn;
  const Vec3 from_q0 = s * da - w;  // A(s) - q0
  const double t = from_q0.dot(db) / db.squaredNorm();
  const bool found = (nn > 0.0) & (s >= 0.0) & (s <= 1.0) & (t >= 0.0) & (t <= 1.0);
  return {found, (from_q0 - t * db).squaredNorm(), s, t};
}

/// Which boundary candidate of segment_segment_distance wins, given the four endpoint-to-
/// segment squared distances in tie order (StartA, EndA, StartB, EndB); returns 0..3.
inline int best_boundary_index(const double (&squared)[4]) {
  int best = 0;
  for (int k = 1; k < 4; ++k) {
    if (squared[k] < squared[best]) {
      best = k;
    }
  }
  return best;
}
}  // namespace detail

}  // namespace vproxq
