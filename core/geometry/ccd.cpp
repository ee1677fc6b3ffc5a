#include "core/geometry/ccd.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace vproxq {
namespace {

// ---- Rounding bound ------------------------------------------------------------------------
//
// Let u = 2^-53 (unit roundoff), M the largest |coordinate k| of the 8 input points, and t, u,
// v box corners (exact dyadic numbers in [0, 1], see kMinWidth, but for t any double in [0, 1]
// after advance_start()), or for u and v any double in [0, 1] (point_within_at_t0()): the bound
// uses only that they are exact inputs of magnitude at most 1. Every rounded operation
// x op y returns (x op y)(1 + e), |e| <= u (no FMA: core/ is built with -ffp-contract=off),
// plus an absolute error below 2^-1075 when the result is subnormal. Per coordinate:
//
//  position at time t:  x(t) = x0 + t * fl(x1 - x0)
//    fl(x1 - x0) = d(1+e1), |d| <= 2M; the product rounds again: |fl(t fl(d)) - t d| <=
//    2M(2u + u^2); the exact x(t) is a convex combination (|x(t)| <= M), so the final sum
//    rounds by at most u(M + 4.1Mu). Total: |x̂(t) - x(t)| <= 5Mu (+ O(u^2) terms), and
//    |x̂(t)| <= M(1 + 6u).
//  vertex–face:  F = ((p - a) - u (b - a)) - v (c - a), all points at time t
//    p - a, b - a, c - a: 5+5 propagated + 2M u rounding        -> 12 Mu each, magnitude 2M
//    u (b - a), v (c - a): 12 propagated + 2M u rounding         -> 14 Mu each
//    (p - a) - u (b - a): 12 + 14 + 4M u rounding                -> 30 Mu, magnitude 4M
//    ... - v (c - a):     30 + 14 + 6M u rounding                -> 50 Mu
//  edge–edge:  F = (a0 + u (a1 - a0)) - (b0 + v (b1 - b0))
//    a1 - a0: 12 Mu; u (a1 - a0): 14 Mu; a0 + ...: 5 + 14 + M u (a convex combination,
//    magnitude M) -> 20 Mu; the same for b; the difference: 40 + 2M u -> 42 Mu.
//
// So |F̂ - F| <= 50 Mu (1 + O(u)) for both kinds; we use ε = 64 Mu = 2^-47 M, plus 2^-1060 for
// the at most ~20 subnormal roundings. This holds for every corner of every box, so the exact
// F over a box lies within [min corner F̂ - ε, max corner F̂ + ε] per coordinate (F is affine
// in each parameter separately: its extremes over a box are at corners).
constexpr double kEpsilonFactor = 0x1p-47;
constexpr double kUnderflowSlack = 0x1p-1060;
// A box side is never split below 2^-50: corners stay multiples of 2^-50 in [0, 1], so they,
// their midpoints and u0 + v0 are exact doubles. A box that cannot be excluded, is not yet
// within δ and cannot be split further is reported as a collision (conservative).
constexpr double kMinWidth = 0x1p-50;
// δ_k is at least this multiple of ε_k, so a small enough box always becomes terminal: a
// corner range that contains 0 within ±ε and has exact width w has rounded width <= w + 2ε,
// so it lies within ±(4ε + w) — inside ±δ once w <= δ - 4ε.
constexpr double kDeltaOverEpsilon = 8;
constexpr double kMaxMagnitude = 0x1p1000;

enum class Kind { VertexFace, EdgeEdge };

struct Box {
  double t0, t1, u0, u1, v0, v1;
};

struct Query {
  Kind kind;
  double x0[4][3];  ///< start positions
  double d[4][3];   ///< fl(end - start)
  double eps[3];
  double delta[3];
  double inv_delta[3];  ///< 1 / delta, rounded (only for choosing the side to split)
};

/// The 4 points at time t, rounded exactly as the derivation above assumes.
inline void positions_at(const Query& q, double t, double out[4][3]) {
  for (int i = 0; i < 4; ++i)
    for (int k = 0; k < 3; ++k) out[i][k] = q.x0[i][k] + t * q.d[i][k];
}

/// Coordinate k of F at (u, v) for the points `x` at one time, exactly as the rounding bound
/// above assumes. Every evaluation of F goes through it (box corners, the points of a box's part
/// inside the triangle, the earliest-face candidate), so all carry the same bound ε_k.
inline double f_at(Kind kind, const double x[4][3], int k, double u, double v) {
  if (kind == Kind::VertexFace) {
    const double pa = x[0][k] - x[1][k];
    const double ba = x[2][k] - x[1][k];
    const double ca = x[3][k] - x[1][k];
    return (pa - u * ba) - v * ca;
  }
  const double ea = x[1][k] - x[0][k];
  const double eb = x[3][k] - x[2][k];
  return (x[0][k] + u * ea) - (x[2][k] + v * eb);
}

/// F at the 4 (u, v) corners of a box, for the points `x` at one time; corner index bit 1 is
/// u high, bit 2 v high (bit 0, time high, is added by the caller).
inline void corner_values(Kind kind, const double x[4][3], const Box& b, double F[8][3], int tbit) {
  for (int k = 0; k < 3; ++k)
    for (int c = 0; c < 4; ++c)
      F[tbit | (c << 1)][k] = f_at(kind, x, k, (c & 1) ? b.u1 : b.u0, (c & 2) ? b.v1 : b.v0);
}

// ---- Exclusion along other directions ------------------------------------------------------
//
// Over a box, F is a trilinear blend of its 8 corner values with non-negative weights summing
// to 1 (affine in each parameter separately), so F takes values only in the convex hull of
// the exact corner values F_c. For any fixed vector w, w . F >= min_c w . F_c over the box:
// if every corner has w . F_c > 0 (or every one < 0), the box holds no root. The coordinate
// axes are the test above; near-degenerate queries (a vertex sliding along a face, edges
// that become parallel or coincide at the end of the step) leave all three coordinate ranges
// straddling 0 until boxes are tiny, and there a few directions taken from the box itself
// exclude it at once:
//   w0: the sum of the corners (where the box's image lies, seen from the origin);
//   w1: w0 without its component along the box's largest spread (the change of F along the
//       parameter that moves it most), which is what separates a long thin image;
//   w2: the cross product of the two largest spreads, the normal of a flat image (the
//       triangle's normal for vertex–face, ea x eb for edge–edge, on small boxes).
// Any w is valid (the directions only propose), so the test is done in rounded arithmetic
// with its own bound. Rounding: w is scaled to max |w_k| = 1 (no overflow: |F| <= 6M <=
// 2^1003). The computed corners F̂_c are within ε_k of the exact F_c per coordinate (above),
// so |w . F̂_c - w . F_c| <= Σ |w_k| ε_k; the rounded dot product fl(w . F̂_c) is within
// γ_3 Σ |w_k| |F̂_ck| <= 2^-51 Σ |w_k| Fmax_k of w . F̂_c (Fmax_k = the largest |F̂_ck|), plus
// at most 2^-1073 of underflow. A box is excluded when every fl(w . F̂_c) exceeds
// E = (Σ |w_k| (ε_k + 2^-51 Fmax_k)) (1 + 2^-40) + 2^-1070 (the factor covers the few
// roundings of E itself), or every one is below -E.
constexpr double kDotRounding = 0x1p-51;

/// Scales w to max |w_k| = 1 and returns the old max |w_k|; 0 if w is zero or not finite (no
/// direction).
inline double unit_max(double w[3]) {
  const double m = std::max({std::abs(w[0]), std::abs(w[1]), std::abs(w[2])});
  if (!(m > 0) || !std::isfinite(m)) return 0;
  const double inv = 1 / m;  // rounded: max |w_k| ends within 2u of 1, which is all we need
  for (int k = 0; k < 3; ++k) w[k] *= inv;
  return m;
}

/// E above: the bound on the error of fl(w . F̂_c) for w scaled by unit_max.
inline double dot_rounding_bound(const double w[3], const double eps[3], const double fmax[3]) {
  double bound = 0;
  for (int k = 0; k < 3; ++k) bound += std::abs(w[k]) * (eps[k] + kDotRounding * fmax[k]);
  return bound * (1 + 0x1p-40) + 0x1p-1070;
}

/// Whether w (scaled by unit_max) separates every one of the n values F from 0 (see above;
/// fmax bounds their |coordinates|).
inline bool excludes(const double w[3], const double (*F)[3], int n, const double eps[3], const double fmax[3]) {
  const double bound = dot_rounding_bound(w, eps, fmax);
  double lo = kInfinity, hi = -kInfinity;
  for (int c = 0; c < n; ++c) {
    const double p = (w[0] * F[c][0] + w[1] * F[c][1]) + w[2] * F[c][2];
    lo = std::min(lo, p);
    hi = std::max(hi, p);
  }
  return lo > bound || hi < -bound;
}

/// The directional tests w0, w1, w2 above on a box's corner values.
bool excluded_along_box_directions(const double F[8][3], const double eps[3], const double fmax[3]) {
  double w0[3] = {0, 0, 0};
  for (int c = 0; c < 8; ++c)
    for (int k = 0; k < 3; ++k) w0[k] += F[c][k];
  if (!(unit_max(w0) > 0)) return false;
  if (excludes(w0, F, 8, eps, fmax)) return true;
  // Spreads: the sum over the 4 corner pairs that differ in one parameter of their change,
  // scaled to max |component| = 1; size[dim] is their max |component| before (0: none).
  double spread[3][3];
  double size[3];
  for (int dim = 0; dim < 3; ++dim) {
    const int bit = 1 << dim;
    for (int k = 0; k < 3; ++k) spread[dim][k] = 0;
    for (int c = 0; c < 8; ++c) {
      if (c & bit) continue;
      for (int k = 0; k < 3; ++k) spread[dim][k] += F[c | bit][k] - F[c][k];
    }
    size[dim] = unit_max(spread[dim]);
  }
  int first = 0;
  for (int dim = 1; dim < 3; ++dim)
    if (size[dim] > size[first]) first = dim;
  if (!(size[first] > 0)) return false;
  int second = first == 0 ? 1 : 0;
  for (int dim = 0; dim < 3; ++dim)
    if (dim != first && size[dim] > size[second]) second = dim;
  const double* a = spread[first];
  const double along = (w0[0] * a[0] + w0[1] * a[1] + w0[2] * a[2]) / (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]);
  double w1[3] = {w0[0] - along * a[0], w0[1] - along * a[1], w0[2] - along * a[2]};
  if (unit_max(w1) > 0 && excludes(w1, F, 8, eps, fmax)) return true;
  if (!(size[second] > 0)) return false;
  const double* b = spread[second];
  double w2[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
  return unit_max(w2) > 0 && excludes(w2, F, 8, eps, fmax);
}

// ---- Vertex–face boxes across the hypotenuse u + v = 1 ------------------------------------
//
// A vertex–face box that reaches past u + v = 1 has corners outside the triangle, where F can
// have roots that the triangle has not. For a degenerate triangle in line with the vertex (F
// then keeps one direction: one equation, not three) F = 0 on a whole surface beyond the
// hypotenuse, t (u + v) = const, and no box across it could be excluded until it was tiny in t,
// u and v at once: on a fuzzed scene, a vertex meeting the end of such a triangle at t = 1
// stopped at the 2^17-box limit and was reported at t = 0.4995. Only the box's part of the
// triangle matters: for fixed t, F is affine in (u, v) jointly, and for fixed (u, v) affine in
// t, so over [t0, t1] x (that part, a polygon of at most 5 vertices) F lies in the hull of its
// values at t0 and at t1 at the polygon's vertices. Those on the hypotenuse are (1 - v, v) or
// (u, 1 - u) with u, v sides of the box: multiples of 2^-50, so exact. F is evaluated there as
// f_at() evaluates a corner (within ε_k of the exact value: the derivation above holds
// for any u, v in [0, 1]), and the coordinate ranges and the direction of their sum then
// exclude the box on the same terms as its corners would.

/// Boxes a vertex–face query evaluates before boxes across the hypotenuse are also judged by
/// their part inside the triangle. Queries decided sooner (nearly all) keep the corner test's
/// answer, which reports a vertex passing within δ just beyond the hypotenuse (tolerance allows
/// it; CcdPipeline.NearMissesWithinTheKernelToleranceAreKept has the pipeline keep such pairs);
/// the surface of roots beyond it is what takes the others to the box limit.
constexpr std::uint32_t kWithinTriangleAfter = 128;

/// Whether the part of vertex–face box b inside the triangle (b.u0 + b.v0 <= 1 < b.u1 + b.v1)
/// holds no root, from the positions x0 at b.t0 and x1 at b.t1 (see above).
bool excluded_within_triangle(const Query& q, const Box& b, const double x0[4][3], const double x1[4][3]) {
  double uv[5][2];
  int n = 0;
  auto add = [&](double u, double v) {
    uv[n][0] = u;
    uv[n][1] = v;
    ++n;
  };
  add(b.u0, b.v0);
  if (b.u1 + b.v0 <= 1) {
    add(b.u1, b.v0);
    add(b.u1, 1 - b.u1);
  } else {
    add(1 - b.v0, b.v0);
  }
  if (b.u0 + b.v1 <= 1) {
    add(1 - b.v1, b.v1);
    add(b.u0, b.v1);
  } else {
    add(b.u0, 1 - b.u0);
  }
  double G[10][3], gmax[3] = {0, 0, 0}, sum[3] = {0, 0, 0};
  for (int k = 0; k < 3; ++k) {
    double lo = kInfinity, hi = -kInfinity;
    for (int end = 0; end < 2; ++end) {
      const double(*x)[3] = end ? x1 : x0;
      for (int i = 0; i < n; ++i) {
        const double f = f_at(Kind::VertexFace, x, k, uv[i][0], uv[i][1]);
        G[end * n + i][k] = f;
        lo = std::min(lo, f);
        hi = std::max(hi, f);
        sum[k] += f;
      }
    }
    if (lo > q.eps[k] || hi < -q.eps[k]) return true;
    gmax[k] = std::max(-lo, hi);
  }
  return unit_max(sum) > 0 && excludes(sum, G, 2 * n, q.eps, gmax);
}

// ---- Exclusion along a direction that moves with t -------------------------------------------
//
// The tests above fix one w for the whole box. When the primitives turn during the step (a
// cloth roll that rotates, with its turns 1e-6 of an edge apart), the image of a box is a
// bow tie: at every t it is a thin sliver beside the origin, but the slivers turn with t and
// the hull of the 8 corners (all a fixed w can use) takes in the origin unless the box is tiny
// in t and in u, v together: some 10^5 boxes along the curve of near-roots. So w may move
// too: w(s) = (1 - s) wa + s wb over the box's t range (s in [0, 1]), wa proposed by the
// corners at the box's t0 and wb by those at its t1, in the same three ways as above.
//   For fixed (u, v), F is affine in t (the points move linearly; u and v multiply them), so
// F(s) = (1 - s) F0 + s F1 with F0, F1 the corner values at the same (u, v); and for fixed t,
// F is affine in (u, v) jointly (no uv term in either kind), so w(s) . F over the box's
// (u, v) range is smallest at one of its 4 (u, v) corners. At a corner, w(s) . F(s) is the
// quadratic with Bernstein coefficients wa . F0, (wa . F1 + wb . F0) / 2, wb . F1 on [0, 1],
// which lies within the range of its coefficients. So when, for all 4 corners, all three
// coefficients exceed 0 (or all are below 0) by their rounding bound, the box holds no root.
//   Rounding: each dot product is bounded as in excludes() with E taken from the larger
// |w_k| of wa and wb (both scaled to max |w_k| = 1). The middle coefficient is tested as
// fl(x + y) > 2E: with x, y within E of the exact products, and fl(x + y) <= (x + y)(1 + u),
// the exact sum is above 2E / (1 + u) - 2E / (1 + 2^-40) > 0 (E carries that factor).

/// The sum of the 4 corners (u, v) of one t face (tbit 0 or 1), and their spreads along u and
/// along v (the change over the 2 corner pairs that differ in that parameter).
inline void face_directions(const double F[8][3], int tbit, double w[3][3]) {
  double sum[3] = {0, 0, 0}, du[3] = {0, 0, 0}, dv[3] = {0, 0, 0};
  for (int c = 0; c < 4; ++c) {
    const int i = tbit | (c << 1);
    for (int k = 0; k < 3; ++k) {
      sum[k] += F[i][k];
      if (c & 1) du[k] += F[i][k] - F[i & ~2][k];
      if (c & 2) dv[k] += F[i][k] - F[i & ~4][k];
    }
  }
  const double su = unit_max(du), sv = unit_max(dv);
  for (int k = 0; k < 3; ++k) w[0][k] = sum[k];
  // w1: the sum without its component along the larger spread.
  const double* a = su >= sv ? du : dv;
  const double aa = a[0] * a[0] + a[1] * a[1] + a[2] * a[2];
  const double along = aa > 0 ? (sum[0] * a[0] + sum[1] * a[1] + sum[2] * a[2]) / aa : 0;
  for (int k = 0; k < 3; ++k) w[1][k] = sum[k] - along * a[k];
  // w2: the normal of the face's image.
  w[2][0] = du[1] * dv[2] - du[2] * dv[1];
  w[2][1] = du[2] * dv[0] - du[0] * dv[2];
  w[2][2] = du[0] * dv[1] - du[1] * dv[0];
}

/// Whether w(s) = (1 - s) wa + s wb (each scaled by unit_max) separates the box's image from 0
/// (see above).
/// `ends_apart` is set when both ends (every b0 and b2) were separated and only the middle
/// coefficients failed: the turning during the box's t range is what keeps it.
inline bool excludes_moving(const double wa[3], const double wb[3], const double F[8][3], const double eps[3],
                            const double fmax[3], bool& ends_apart) {
  double bound = 0;
  for (int k = 0; k < 3; ++k)
    bound += std::max(std::abs(wa[k]), std::abs(wb[k])) * (eps[k] + kDotRounding * fmax[k]);
  bound = bound * (1 + 0x1p-40) + 0x1p-1070;
  const double twice = 2 * bound;
  bool positive = true, negative = true, ends_positive = true, ends_negative = true;
  for (int c = 0; c < 4 && (ends_positive || ends_negative); ++c) {
    const double* f0 = F[c << 1];
    const double* f1 = F[(c << 1) | 1];
    const double b0 = (wa[0] * f0[0] + wa[1] * f0[1]) + wa[2] * f0[2];
    const double b2 = (wb[0] * f1[0] + wb[1] * f1[1]) + wb[2] * f1[2];
    const double b1 = ((wa[0] * f1[0] + wa[1] * f1[1]) + wa[2] * f1[2]) + ((wb[0] * f0[0] + wb[1] * f0[1]) + wb[2] * f0[2]);
    ends_positive = ends_positive && b0 > bound && b2 > bound;
    ends_negative = ends_negative && b0 < -bound && b2 < -bound;
    positive = positive && ends_positive && b1 > twice;
    negative = negative && ends_negative && b1 < -twice;
  }
  ends_apart = ends_apart || ends_positive || ends_negative;
  return positive || negative;
}

/// The moving-direction test with the three directions proposed by the box's two t faces;
/// `ends_apart` as in excludes_moving() for any of them.
[[gnu::noinline]] bool excluded_along_moving_directions(const double F[8][3], const double eps[3], const double fmax[3],
                                      bool& ends_apart) {
  double wa[3][3], wb[3][3];
  face_directions(F, 0, wa);
  face_directions(F, 1, wb);
  for (int i = 0; i < 3; ++i) {
    if (!(unit_max(wa[i]) > 0) || !(unit_max(wb[i]) > 0)) continue;
    // Any wa and wb are valid; turned the same way, they can agree on a side.
    if (wa[i][0] * wb[i][0] + wa[i][1] * wb[i][1] + wa[i][2] * wb[i][2] < 0)
      for (int k = 0; k < 3; ++k) wb[i][k] = -wb[i][k];
    if (excludes_moving(wa[i], wb[i], F, eps, fmax, ends_apart)) return true;
  }
  return false;
}

/// Boxes a query evaluates before it also tries the moving directions; the tries after which
/// they must have excluded at least 1 box in kMovingYield to go on being tried.
constexpr std::uint32_t kMovingAfter = 128;
constexpr std::uint32_t kMovingTrial = 64;
constexpr std::uint32_t kMovingYield = 16;

// ---- A point within δ on the box's earliest face ------------------------------------------
//
// A box is a hit when it is not excluded and some point of it at its own t0 is certified within
// δ: |F(t0, u, v)_k| <= δ_k for one (u, v) of its range (in the triangle for vertex–face). That
// is the certificate `inside` gives (there for every point of the box), so a hit means the same
// (the primitives come within δ_k on every axis at the reported time, and no root is earlier:
// the search invariant in solve() is unchanged), but it needs t refined only until t0 reaches
// the contact, not u and v until the whole box fits within δ. The candidate is the minimizer of
// |F(t0, ., .)| over the plane (2 x 2 normal equations, in rounded arithmetic: any (u, v) is
// valid, the choice only proposes; for (nearly) parallel edges, whose minimizers form a line,
// the one at the box's middle u), clamped into the box's range; F̂ there is within ε_k of the
// exact F (the derivation above holds for any u, v in [0, 1]), so |F̂_k| + ε_k <= δ_k certifies
// it (the rounding of that sum is within the 2^-40 widening the pipeline's margins carry, see
// ccd_max_tolerance()). On the funnel scene's CCD (steps 10-19) it took the boxes evaluated from
// 4.36 to 3.55 million, with the search order below.

/// Whether a point of the box at its t0 (positions `x`, corner values F[c], c even) is certified
/// within δ, as above.
bool point_within_at_t0(const Query& q, const Box& b, const double x[4][3], const double F[8][3]) {
  // No point of the t0 face is within δ_k when all 4 of its corners lie beyond δ_k on one side
  // (its image lies in their hull): a cheap first test.
  for (int k = 0; k < 3; ++k) {
    double lo = F[0][k], hi = F[0][k];
    for (int c = 2; c < 8; c += 2) {
      lo = std::min(lo, F[c][k]);
      hi = std::max(hi, F[c][k]);
    }
    if (lo > q.delta[k] || hi < -q.delta[k]) return false;
  }
  // F(t0, u, v) = A + u B + v C.
  double A[3], B[3], C[3];
  for (int k = 0; k < 3; ++k) {
    if (q.kind == Kind::VertexFace) {
      A[k] = x[0][k] - x[1][k];
      B[k] = x[1][k] - x[2][k];
      C[k] = x[1][k] - x[3][k];
    } else {
      A[k] = x[0][k] - x[2][k];
      B[k] = x[1][k] - x[0][k];
      C[k] = x[2][k] - x[3][k];
    }
  }
  const double bb = B[0] * B[0] + B[1] * B[1] + B[2] * B[2];
  const double cc = C[0] * C[0] + C[1] * C[1] + C[2] * C[2];
  const double bc = B[0] * C[0] + B[1] * C[1] + B[2] * C[2];
  const double ab = A[0] * B[0] + A[1] * B[1] + A[2] * B[2];
  const double ac = A[0] * C[0] + A[1] * C[1] + A[2] * C[2];
  const double det = bb * cc - bc * bc;
  double u, v;
  if (det > 0x1p-40 * bb * cc) {
    u = std::clamp((bc * ac - cc * ab) / det, b.u0, b.u1);
    v = std::clamp((bc * ab - bb * ac) / det, b.v0, b.v1);
  } else if (cc > 0) {
    // (Nearly) parallel: the minimizers form a line; the one at the box's middle u.
    u = 0.5 * (b.u0 + b.u1);
    v = std::clamp(-(ac + u * bc) / cc, b.v0, b.v1);
  } else {
    return false;
  }
  if (!(u >= 0 && u <= 1 && v >= 0 && v <= 1)) return false;
  if (q.kind == Kind::VertexFace && !(u + v < 1)) {
    // Beyond the hypotenuse, or on it: the candidate moves back just inside it within the box
    // (u first, then v). A contact on the triangle's edge bc (p in line with b and c, or at
    // corner b or c) has its minimizer on u + v = 1 itself, and without this the box there
    // could only become a hit once it lay within δ whole: a fuzzed query of a vertex sliding
    // along bc in the triangle's plane, meeting corner c first, ran to the box limit.
    const double below_one = 1 - 0x1p-52;
    u = std::max(b.u0, std::min(u, below_one - v));
    if (!(u + v < 1)) v = std::max(b.v0, below_one - u);
  }
  // fl(u + v) < 1 implies u + v < 1 (rounding is monotone and 1 is a double).
  if (q.kind == Kind::VertexFace && !(u + v < 1)) return false;
  for (int k = 0; k < 3; ++k) {
    if (!(std::abs(f_at(q.kind, x, k, u, v)) + q.eps[k] <= q.delta[k])) return false;
  }
  return true;
}

// ---- Advancing a box's start past a part shown apart -----------------------------------------
//
// Near a contact the search used to halve t some 20 times on the way down, evaluating each
// earlier half only to exclude it. Instead, when all four corners of a box's t0 face lie on one
// side of a direction w (proposed by that face, as in face_directions()), the earliest part of
// the box that keeps them there can be cut off at once: for fixed (u, v), w . F is affine in t,
// so corner c's projection reaches the bound at s_c = (p0 - 2E) / (p0 - p1) of the box's time
// range (p0, p1 its projections at t0 and t1), and over the sub-box [t0, ts] x (u, v range) with
// ts just before the smallest s_c every corner stays beyond E. That is then checked, not
// assumed: the sub-box's corner values (those at t0 are the box's, those at ts evaluated afresh,
// exactly as corner_values() evaluates any box) go through excludes() with w, the fixed
// direction test above, rigorous for any w and any t in [0, 1]. On success the sub-box holds no
// root, the box becomes [ts, t1] (its t0 corners are the ones just evaluated) and is looked at
// again, so the search invariant in solve() holds. The advance goes up to the contact itself,
// where the earliest-face certificate then decides at once (stopping where the box first comes
// within δ instead left the old refinement to do: more boxes than without advancing). On the
// funnel scene's CCD (steps 10-19) this took the boxes evaluated from 3.55 to 1.39 million (plus
// 0.44 million advances, each costing about half a box), and CCD's exact stage per frame (steps
// 10-29, median of 4 alternating runs) from 157.3 to 147.1 ms on one thread and from 81.8 to
// 78.1 ms on two: the kernel is now a small part of CCD. The kernel tests' degenerate colliding
// queries went from 257 to 134 ms, the touching turning layers from 582 to 327 ms.
//   Small advances pay too: near a contact each one moves t0 most of the way to where the
// corners would reach the bound, as conservative advancement does, where a split in t only
// halves the range. Taking every share from 2^-16 up (at first only from 1/16) took the boxes
// evaluated on the report's funnel scene (vproxq-gen funnel --seed 1 --frames 12, steps 8-11,
// 545,711 queries) from 1.17 to 0.63 million (advances 0.46 to 0.52 million), CCD's exact
// stage per step (steps 1-11, medians of 3, two rounds) from 304/303 to 249/243 ms on one
// thread and from 206/187 to 149/146 ms on two (cloth-ball 88/70 to 53/54 on two, skirt
// unchanged), the kernel tests' degenerate colliding queries from 113 to 26 ms and the touching
// turning layers from 287 to 41 ms. Smaller shares (2^-24, 0) measured the same.
constexpr int kMaxAdvances = 8;          ///< per box popped from the stack
constexpr double kAdvanceMin = 0x1p-16;  ///< smallest share of the time range worth advancing

/// Advances b.t0 past a part of the box shown apart (above); updates x0 and F's t0 corners.
bool advance_start(const Query& q, Kind kind, Box& b, double x0[4][3], double F[8][3], const double fmax[3]) {
  double w[3][3];
  face_directions(F, 0, w);
  double share = 0, chosen[3] = {0, 0, 0};
  for (int i = 0; i < 3; ++i) {
    if (!(unit_max(w[i]) > 0)) continue;
    const double margin = 2 * dot_rounding_bound(w[i], q.eps, fmax);
    double p0[4], p1[4];
    bool above = true, below = true;
    for (int c = 0; c < 4; ++c) {
      const double* f0 = F[c << 1];
      const double* f1 = F[(c << 1) | 1];
      p0[c] = (w[i][0] * f0[0] + w[i][1] * f0[1]) + w[i][2] * f0[2];
      p1[c] = (w[i][0] * f1[0] + w[i][1] * f1[1]) + w[i][2] * f1[2];
      above = above && p0[c] > margin;
      below = below && p0[c] < -margin;
    }
    if (!above && !below) continue;
    const double sign = above ? 1 : -1;
    double s = 1;
    for (int c = 0; c < 4; ++c) {
      const double a = sign * p0[c], z = sign * p1[c];
      if (z <= margin) s = std::min(s, (a - margin) / (a - z));
    }
    if (s > share) {
      share = s;
      for (int k = 0; k < 3; ++k) chosen[k] = sign * w[i][k];
    }
  }
  if (!(share >= kAdvanceMin)) return false;
  const double ts = b.t0 + 0.999 * share * (b.t1 - b.t0);
  if (!(ts > b.t0 && ts < b.t1)) return false;
  double xs[4][3], G[8][3], gmax[3] = {0, 0, 0};
  positions_at(q, ts, xs);
  corner_values(kind, xs, b, G, 1);  // the sub-box's end corners; its start corners are F's
  for (int c = 0; c < 8; c += 2)
    for (int k = 0; k < 3; ++k) G[c][k] = F[c][k];
  for (int c = 0; c < 8; ++c)
    for (int k = 0; k < 3; ++k) gmax[k] = std::max(gmax[k], std::abs(G[c][k]));
  if (!excludes(chosen, G, 8, q.eps, gmax)) return false;
  b.t0 = ts;
  for (int c = 0; c < 8; c += 2)
    for (int k = 0; k < 3; ++k) F[c][k] = G[c | 1][k];
  std::copy(&xs[0][0], &xs[0][0] + 12, &x0[0][0]);
  return true;
}

CcdResult conservative_hit(double t, std::uint32_t boxes) {
  CcdResult r;
  r.collides = true;
  r.toi = t;
  r.hit_limit = true;
  r.boxes = boxes;
  return r;
}

CcdResult solve(Kind kind, const std::array<Vec3, 4>& start, const std::array<Vec3, 4>& end) {
  Query q;
  q.kind = kind;
  double extent = 0;
  for (int k = 0; k < 3; ++k) {
    double m = 0, lo = kInfinity, hi = -kInfinity;
    for (int i = 0; i < 4; ++i) {
      const double a = start[static_cast<size_t>(i)][k], b = end[static_cast<size_t>(i)][k];
      if (!std::isfinite(a) || !std::isfinite(b)) return conservative_hit(0, 0);
      m = std::max({m, std::abs(a), std::abs(b)});
      lo = std::min({lo, a, b});
      hi = std::max({hi, a, b});
      q.x0[i][k] = a;
      q.d[i][k] = b - a;
    }
    if (m > kMaxMagnitude) return conservative_hit(0, 0);
    q.eps[k] = m * kEpsilonFactor + kUnderflowSlack;
    extent = std::max(extent, hi - lo);
  }
  for (int k = 0; k < 3; ++k) {
    q.delta[k] = std::max(kCcdRelativeTolerance * extent, kDeltaOverEpsilon * q.eps[k]);
    q.inv_delta[k] = 1 / q.delta[k];
  }

  // Depth-first search with pruning. `best` is the smallest t0 of the boxes found within δ
  // so far; a box with t0 >= best cannot improve the answer and is dropped. Invariant: every
  // root (t*, u*, v*) lies in a box on the stack, or in a dropped box (then best <= t0 <= t*),
  // or in a box found within δ (best <= t*). So at the end best <= t* for every root, and
  // when the search stops at the box limit, min(best, t0 of every box left) is as well.
  // A box whose t range reaches past `best` is split in t first: its part beyond best is
  // dropped at once, which keeps degenerate cases (a curve or surface of roots, e.g. parallel
  // edges) from being refined all along the curve.
  thread_local std::vector<Box> stack;  // one per thread, reused: queries are many and small
  stack.clear();
  stack.push_back({0, 1, 0, 1, 0, 1});
  CcdResult result;
  double best = kInfinity;
  std::uint32_t moving_tries = 0, moving_hits = 0;
  double x0[4][3], x1[4][3];
  double F[8][3];
  while (!stack.empty()) {
    Box b = stack.back();
    stack.pop_back();
    if (b.t0 >= best) continue;
    if (result.boxes == kCcdMaxBoxes) {
      double t = std::min(best, b.t0);
      for (const Box& r : stack) t = std::min(t, r.t0);
      return conservative_hit(t, result.boxes);
    }
    ++result.boxes;
    if (kind == Kind::VertexFace && b.u0 + b.v0 > 1) continue;  // outside the triangle

    positions_at(q, b.t0, x0);
    corner_values(kind, x0, b, F, 0);
    positions_at(q, b.t1, x1);
    corner_values(kind, x1, b, F, 1);

    // The box is excluded, a hit, or to be split; before it is split, its start may be
    // advanced past a part shown apart (advance_start()) and the rest looked at again.
    bool decided = false;  // excluded, or a hit
    bool ends_apart = false;
    for (int advances = 0;; ++advances) {
      bool inside = true;
      bool excluded = false;
      double fmax[3];
      for (int k = 0; k < 3 && !excluded; ++k) {
        double lo = F[0][k], hi = F[0][k];
        for (int c = 1; c < 8; ++c) {
          lo = std::min(lo, F[c][k]);
          hi = std::max(hi, F[c][k]);
        }
        if (lo > q.eps[k] || hi < -q.eps[k]) excluded = true;
        if (hi + q.eps[k] > q.delta[k] || lo - q.eps[k] < -q.delta[k]) inside = false;
        fmax[k] = std::max(-lo, hi);
      }
      if (excluded || excluded_along_box_directions(F, q.eps, fmax) ||
          (kind == Kind::VertexFace && result.boxes > kWithinTriangleAfter && b.u1 + b.v1 > 1 &&
           excluded_within_triangle(q, b, x0, x1))) {
        decided = true;
        break;
      }
      // The moving directions cost about as much again as the rest of a box; queries decided
      // within kMovingAfter boxes (nearly all) do without them, and so does a query on which
      // they have excluded fewer than 1 box in kMovingYield after kMovingTrial tries.
      ends_apart = false;
      if (result.boxes > kMovingAfter && (moving_tries < kMovingTrial || moving_hits * kMovingYield >= moving_tries)) {
        ++moving_tries;
        if (excluded_along_moving_directions(F, q.eps, fmax, ends_apart)) {
          ++moving_hits;
          decided = true;
          break;
        }
      }
      if (inside || point_within_at_t0(q, b, x0, F)) {
        best = b.t0;  // b.t0 < best: checked when popped, and after each advance
        decided = true;
        break;
      }
      if (advances == kMaxAdvances || !advance_start(q, kind, b, x0, F, fmax)) break;
      if (b.t0 >= best) {
        decided = true;
        break;
      }
    }
    if (decided) continue;

    // Which side to split: t when the box reaches past `best`, or for edge–edge when the
    // moving directions separated both ends of the box but not its middle (the turning is what
    // keeps it: halving t quarters that term; for vertex–face this made some queries 4x
    // slower and none much faster); otherwise the side along which F varies most relative to
    // δ (it shrinks the corner range fastest). Corner c and c | bit differ only in parameter
    // `dim` (bit = 1 << dim).
    const double width[3] = {b.t1 - b.t0, b.u1 - b.u0, b.v1 - b.v0};
    int split = -1;
    if ((b.t1 > best || (ends_apart && kind == Kind::EdgeEdge)) && width[0] > kMinWidth) {
      split = 0;
    } else {
      double best_var = -1;
      for (int dim = 0; dim < 3; ++dim) {
        if (width[dim] <= kMinWidth) continue;
        const int bit = 1 << dim;
        double var = 0;
        for (int c = 0; c < 8; ++c) {
          if (c & bit) continue;
          for (int k = 0; k < 3; ++k)
            var = std::max(var, std::abs(F[c | bit][k] - F[c][k]) * q.inv_delta[k]);
        }
        var *= 1 + width[dim];  // ties (no variation) go to the wider side
        if (var > best_var) {
          best_var = var;
          split = dim;
        }
      }
    }
    if (split < 0) {
      // Cannot be split further nor excluded: count it as a hit at its t0 (conservative).
      result.hit_limit = true;
      best = b.t0;
      continue;
    }
    Box lo = b, hi = b;
    if (split == 0) {
      const double m = 0.5 * (b.t0 + b.t1);
      lo.t1 = m;
      hi.t0 = m;
    } else if (split == 1) {
      const double m = 0.5 * (b.u0 + b.u1);
      lo.u1 = m;
      hi.u0 = m;
    } else {
      const double m = 0.5 * (b.v0 + b.v1);
      lo.v1 = m;
      hi.v0 = m;
    }
    // The half searched first goes onto the stack last. Split in t: the earlier half, so `best`
    // drops early and prunes more. Split in u or v: the half whose t0 face's image lies nearer
    // 0 (its centre, in units of δ), where the earliest contact more likely is: once a hit at
    // the box's t0 is found, the other half (same t0) is dropped unsearched. F is affine along
    // u and along v, so a half's corner sum is (3 S0 + S1) / 2 or (S0 + 3 S1) / 2, S0 and S1 the
    // sums over the parent's t0 corners on either side. On the funnel scene's CCD (steps 10-19)
    // this took the boxes evaluated from 6.44 to 4.36 million (edge–edge: 5.34 to 3.36; the
    // queries of nearly parallel edges in near contact took up to 81,000 boxes).
    bool lo_first = true;
    if (split != 0) {
      const int bit = 1 << split;
      double near_lo = 0, near_hi = 0;
      for (int k = 0; k < 3; ++k) {
        double s0 = 0, s1 = 0;
        for (int c = 0; c < 8; c += 2) (c & bit ? s1 : s0) += F[c][k];
        near_lo = std::max(near_lo, std::abs(3 * s0 + s1) * q.inv_delta[k]);
        near_hi = std::max(near_hi, std::abs(s0 + 3 * s1) * q.inv_delta[k]);
      }
      lo_first = !(near_hi < near_lo);
    }
    stack.push_back(lo_first ? hi : lo);
    stack.push_back(lo_first ? lo : hi);
  }
  if (best < kInfinity) {
    result.collides = true;
    result.toi = best;
  }
  return result;
}

}  // namespace

CcdResult vertex_face_ccd(const std::array<Vec3, 4>& start, const std::array<Vec3, 4>& end) {
  return solve(Kind::VertexFace, start, end);
}

CcdResult edge_edge_ccd(const std::array<Vec3, 4>& start, const std::array<Vec3, 4>& end) {
  return solve(Kind::EdgeEdge, start, end);
}

double ccd_share_factor() { return 1 / (1 - 2 * kCcdRelativeTolerance); }

double ccd_tolerance_share(double extent, double magnitude) {
  // ccd_max_tolerance(S, m) <= (a S + 8 eps(m)) (1 + 2^-40) with a = kCcdRelativeTolerance (a
  // max is below the sum), and eps(max(x, y)) <= eps(x) + eps(y). With S <= sA + sB + M:
  // M (1 - a (1 + 2^-40)) <= the terms of A + those of B; dividing by 1 - 2a instead of
  // 1 - a (1 + 2^-40) leaves room for the rounding of these few operations.
  const double eps = magnitude * kEpsilonFactor + kUnderflowSlack;
  return (kCcdRelativeTolerance * extent + kDeltaOverEpsilon * eps) * (1 + 0x1p-40) * ccd_share_factor();
}

double ccd_max_tolerance(double extent, double magnitude) {
  const double eps = magnitude * kEpsilonFactor + kUnderflowSlack;
  // The widening by 2^-40 absorbs the rounding of these few operations (they are monotone,
  // so a query inside the given bounds never gets a larger value).
  return std::max(kCcdRelativeTolerance * extent, kDeltaOverEpsilon * eps) * (1 + 0x1p-40);
}

}  // namespace vproxq
