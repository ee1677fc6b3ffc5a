// Exact orientation predicates: a static-bound floating-point filter, and an exact fallback in
// floating-point expansion arithmetic.
//
// Reference: J. R. Shewchuk, "Adaptive Precision Floating-Point Arithmetic and Fast Robust
// Geometric Predicates", Discrete & Computational Geometry 18:305-363, 1997. The algorithms
// (two-sum, two-product, expansion sum and scaling) and the filter bounds are from that paper;
// the code is written for this project.
//
// Assumptions: IEEE-754 binary64 arithmetic, round-to-nearest-even, no excess precision (x86-64
// SSE2 / AArch64), and no contraction of a*b+c into a fused multiply-add by the compiler. The
// last one matters for the filter, whose bound counts one rounding per operation: every product
// below is stored in its own variable before it is added, so even a compiler that contracts
// within an expression (clang's default -ffp-contract=on) has nothing to fuse.
#include "core/geometry/predicates.hpp"

#include <cmath>

namespace vproxq {
namespace {

/// Unit roundoff of binary64 with round-to-nearest: 2^-53.
constexpr double kEpsilon = 0x1p-53;

/// Filter constant of orient2d (Shewchuk 1997, sec. 4.3, "ccwerrboundA").
/// The determinant ux*vy - uy*vx is computed from rounded differences u = b-a, v = c-a. Each
/// monomial goes through 3 roundings that matter for the sign (its two differences and its
/// product; the final subtraction rounds the result, which never changes its sign), so the
/// error is at most (3e + O(e^2)) times the permanent |ux*vy| + |uy*vx|. The 16e^2 term covers
/// the second-order terms and the rounding of the computed permanent and of the bound itself.
constexpr double kOrient2dErrorBound = (3.0 + 16.0 * kEpsilon) * kEpsilon;

/// Filter constant of orient3d (Shewchuk 1997, sec. 4.3, "o3derrboundA").
/// det = uz*(vx*wy - vy*wx) + ... from rounded differences: the longest path of a monomial has
/// 7 sign-relevant roundings (3 differences, product, 2x2 minor, times the third factor, first
/// of the two additions; the last addition rounds the result and keeps its sign), so the error
/// is at most (7e + 56e^2) times the permanent sum |uz|*(|vx*wy| + |vy*wx|) + ...
constexpr double kOrient3dErrorBound = (7.0 + 56.0 * kEpsilon) * kEpsilon;

// When the filter's bound is zero, every product in the permanent was computed as zero. A
// difference of two doubles rounds to zero only when they are equal, and in the documented
// coordinate range no product of nonzero differences underflows (they are at least 2^-252, so a
// product of three is at least 2^-756), so each monomial of the determinant is exactly zero and
// so is the determinant: no need for the exact fallback. This is the common degenerate case of
// meshes (flat sheets on an axis-aligned plane, vertices on grid lines), which otherwise paid
// for expansion arithmetic on every coplanar or collinear test.

thread_local PredicateCounters g_counters;

// ---- error-free transformations -------------------------------------------------------------

/// a + b = sum + err exactly, with sum = fl(a + b) (Knuth's branch-free two-sum).
inline void two_sum(double a, double b, double& sum, double& err) {
  sum = a + b;
  const double b_virtual = sum - a;
  const double a_virtual = sum - b_virtual;
  const double b_round = b - b_virtual;
  const double a_round = a - a_virtual;
  err = a_round + b_round;
}

/// a * b = prod + err exactly, with prod = fl(a * b) (the fma computes the rounding error).
inline void two_product(double a, double b, double& prod, double& err) {
  prod = a * b;
  err = std::fma(a, b, -prod);
}

// ---- expansions ------------------------------------------------------------------------------
// An expansion is an array of doubles whose exact sum is the value it represents. The arrays
// here are nonoverlapping, ordered by increasing magnitude, and contain no zeros except that
// the value 0 is the one-element expansion {0}. Then the sign of the value is the sign of the
// last (largest) element.

/// Appends err to h unless it is zero; returns the new length.
inline int push_nonzero(double* h, int len, double value) {
  if (value != 0.0) {
    h[len++] = value;
  }
  return len;
}

/// Closes an expansion: appends the final running sum unless it is zero and the expansion is
/// otherwise non-empty (keeps {0} for the value zero).
inline int close_expansion(double* h, int len, double q) {
  if (q != 0.0 || len == 0) {
    h[len++] = q;
  }
  return len;
}

/// The exact difference a - b as an expansion (1 or 2 elements); returns its length.
int difference_expansion(double a, double b, double* h) {
  double sum = 0.0;
  double err = 0.0;
  two_sum(a, -b, sum, err);
  int len = push_nonzero(h, 0, err);
  return close_expansion(h, len, sum);
}

/// h = e + f (Shewchuk's FAST-EXPANSION-SUM with zero elimination, two-sum at every step).
/// The inputs are merged by increasing magnitude, then a running sum sweeps through them,
/// shedding its exact rounding errors as output elements. h may not alias e or f; its capacity
/// must be at least elen + flen.
int expansion_sum(int elen, const double* e, int flen, const double* f, double* h) {
  int ei = 0;
  int fi = 0;
  // Next element in merged order: the smaller magnitude first (ties: e first).
  auto next = [&]() {
    if (fi >= flen || (ei < elen && std::fabs(e[ei]) <= std::fabs(f[fi]))) {
      return e[ei++];
    }
    return f[fi++];
  };
  double q = next();
  int hlen = 0;
  while (ei < elen || fi < flen) {
    double sum = 0.0;
    double err = 0.0;
    two_sum(q, next(), sum, err);
    hlen = push_nonzero(h, hlen, err);
    q = sum;
  }
  return close_expansion(h, hlen, q);
}

/// h = e * b (Shewchuk's SCALE-EXPANSION with zero elimination). h may not alias e; its
/// capacity must be at least 2 * elen.
int scale_expansion(int elen, const double* e, double b, double* h) {
  double q = 0.0;
  double err = 0.0;
  two_product(e[0], b, q, err);
  int hlen = push_nonzero(h, 0, err);
  for (int i = 1; i < elen; ++i) {
    double prod_hi = 0.0;
    double prod_lo = 0.0;
    two_product(e[i], b, prod_hi, prod_lo);
    double sum = 0.0;
    two_sum(q, prod_lo, sum, err);
    hlen = push_nonzero(h, hlen, err);
    two_sum(prod_hi, sum, q, err);  // Shewchuk uses fast-two-sum here; two-sum is equal and safe
    hlen = push_nonzero(h, hlen, err);
  }
  return close_expansion(h, hlen, q);
}

/// Largest expansion length handled by expansion_product (see the capacities below).
constexpr int kMaxProductLength = 64;

/// h = e * f: the sum over the elements of f of e scaled by that element. Capacity of h must be
/// at least 2 * elen * flen; elen * flen <= kMaxProductLength / 2.
int expansion_product(int elen, const double* e, int flen, const double* f, double* h) {
  double scaled[kMaxProductLength];
  double acc[2][kMaxProductLength];
  int acc_len = scale_expansion(elen, e, f[0], acc[0]);
  int cur = 0;
  for (int j = 1; j < flen; ++j) {
    const int slen = scale_expansion(elen, e, f[j], scaled);
    acc_len = expansion_sum(acc_len, acc[cur], slen, scaled, acc[1 - cur]);
    cur = 1 - cur;
  }
  for (int i = 0; i < acc_len; ++i) {
    h[i] = acc[cur][i];
  }
  return acc_len;
}

/// Negates an expansion in place (exact).
void negate(int len, double* e) {
  for (int i = 0; i < len; ++i) {
    e[i] = -e[i];
  }
}

int sign_of(double x) { return (x > 0.0) - (x < 0.0); }

/// Sign of the value of an expansion: the sign of its largest (last) element.
int expansion_sign(int len, const double* e) { return sign_of(e[len - 1]); }

/// A 1..2 element expansion holding an exact coordinate difference.
struct Diff {
  double v[2];
  int len;
};

Diff exact_difference(double a, double b) {
  Diff d{};
  d.len = difference_expansion(a, b, d.v);
  return d;
}

/// Exact 2x2 minor p0*q1 - p1*q0 of differences (at most 16 elements).
int exact_minor(const Diff& p0, const Diff& q1, const Diff& p1, const Diff& q0, double* h) {
  double left[8];
  double right[8];
  const int llen = expansion_product(p0.len, p0.v, q1.len, q1.v, left);
  const int rlen = expansion_product(p1.len, p1.v, q0.len, q0.v, right);
  negate(rlen, right);
  return expansion_sum(llen, left, rlen, right, h);
}

int orient2d_exact(const Vec2& a, const Vec2& b, const Vec2& c) {
  ++g_counters.orient2d_exact;
  const Diff ux = exact_difference(b[0], a[0]);
  const Diff uy = exact_difference(b[1], a[1]);
  const Diff vx = exact_difference(c[0], a[0]);
  const Diff vy = exact_difference(c[1], a[1]);
  double det[16];
  const int len = exact_minor(ux, vy, uy, vx, det);
  return expansion_sign(len, det);
}

/// The term factor * minor, exact (at most 64 elements).
int exact_term(const Diff& factor, const double* minor, int minor_len, double* h) {
  return expansion_product(minor_len, minor, factor.len, factor.v, h);
}

int orient3d_exact(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  ++g_counters.orient3d_exact;
  Diff u[3];
  Diff v[3];
  Diff w[3];
  for (int k = 0; k < 3; ++k) {
    u[k] = exact_difference(b[k], a[k]);
    v[k] = exact_difference(c[k], a[k]);
    w[k] = exact_difference(d[k], a[k]);
  }
  // det = ux*(vy*wz - vz*wy) + uy*(vz*wx - vx*wz) + uz*(vx*wy - vy*wx)
  double minor[16];
  double term_x[64];
  double term_y[64];
  double term_z[64];
  int mlen = exact_minor(v[1], w[2], v[2], w[1], minor);
  const int xlen = exact_term(u[0], minor, mlen, term_x);
  mlen = exact_minor(v[2], w[0], v[0], w[2], minor);
  const int ylen = exact_term(u[1], minor, mlen, term_y);
  mlen = exact_minor(v[0], w[1], v[1], w[0], minor);
  const int zlen = exact_term(u[2], minor, mlen, term_z);
  double xy[128];
  double det[192];
  const int xylen = expansion_sum(xlen, term_x, ylen, term_y, xy);
  const int len = expansion_sum(xylen, xy, zlen, term_z, det);
  return expansion_sign(len, det);
}

}  // namespace

PredicateCounters& predicate_counters() { return g_counters; }

int orient2d(const Vec2& a, const Vec2& b, const Vec2& c) {
  const double ux = b[0] - a[0];
  const double uy = b[1] - a[1];
  const double vx = c[0] - a[0];
  const double vy = c[1] - a[1];
  const double left = ux * vy;
  const double right = uy * vx;
  const double det = left - right;
  const double bound = kOrient2dErrorBound * (std::fabs(left) + std::fabs(right));
  if (det > bound || -det > bound) {
    return sign_of(det);
  }
  // Both products zero: an exact zero (see above, after kOrient3dErrorBound).
  if (bound == 0) return 0;
  return orient2d_exact(a, b, c);
}

int orient2d_projected(const Vec3& a, const Vec3& b, const Vec3& c, int drop_axis) {
  const int i = (drop_axis + 1) % 3;
  const int j = (drop_axis + 2) % 3;
  return orient2d(Vec2(a[i], a[j]), Vec2(b[i], b[j]), Vec2(c[i], c[j]));
}

int orient3d(const Vec3& a, const Vec3& b, const Vec3& c, const Vec3& d) {
  const double ux = b[0] - a[0];
  const double uy = b[1] - a[1];
  const double uz = b[2] - a[2];
  const double vx = c[0] - a[0];
  const double vy = c[1] - a[1];
  const double vz = c[2] - a[2];
  const double wx = d[0] - a[0];
  const double wy = d[1] - a[1];
  const double wz = d[2] - a[2];
  // Products in their own variables: no fused multiply-add may change the rounding count.
  const double vy_wz = vy * wz;
  const double vz_wy = vz * wy;
  const double vz_wx = vz * wx;
  const double vx_wz = vx * wz;
  const double vx_wy = vx * wy;
  const double vy_wx = vy * wx;
  const double minor_x = vy_wz - vz_wy;
  const double minor_y = vz_wx - vx_wz;
  const double minor_z = vx_wy - vy_wx;
  const double term_x = ux * minor_x;
  const double term_y = uy * minor_y;
  const double term_z = uz * minor_z;
  const double det = (term_x + term_y) + term_z;
  const double perm_x = std::fabs(vy_wz) + std::fabs(vz_wy);
  const double perm_y = std::fabs(vz_wx) + std::fabs(vx_wz);
  const double perm_z = std::fabs(vx_wy) + std::fabs(vy_wx);
  const double permanent_x = std::fabs(ux) * perm_x;
  const double permanent_y = std::fabs(uy) * perm_y;
  const double permanent_z = std::fabs(uz) * perm_z;
  const double permanent = (permanent_x + permanent_y) + permanent_z;
  const double bound = kOrient3dErrorBound * permanent;
  if (det > bound || -det > bound) {
    return sign_of(det);
  }
  // Every product zero: an exact zero (see above, after kOrient3dErrorBound).
  if (bound == 0) return 0;
  return orient3d_exact(a, b, c, d);
}

}  // namespace vproxq
