#pragma once
// Conservative continuous collision detection of the elementary primitive pairs (paper 3.2,
// Bridson et al. 2002): a vertex against a triangle, and an edge against an edge, each of
// their points moving linearly from its start to its end position over t in [0, 1].
//
// Method: an inclusion-based root finder in the style of Wang et al. 2021 ("Tight
// Inclusion"). A collision is a root of the difference function F(t, u, v) in R^3 over the
// parameter domain (vertex–face: t in [0,1], u, v >= 0, u + v <= 1; edge–edge: [0,1]^3).
// F is affine in each parameter separately, so over a parameter box each coordinate of F
// takes its extreme values at the 8 box corners. The finder evaluates F at the corners in
// double precision, widens the corner range by a derived rounding bound ε (ccd.cpp), and
// discards a box whose widened range misses 0 in some coordinate: that box provably holds no
// root. Since F over a box lies in the convex hull of its corner values, the same holds along
// any direction: a few directions taken from the corners (ccd.cpp) discard the boxes of
// near-degenerate queries (sliding contact, edges that become parallel or coincide) that no
// coordinate range can, long before the boxes are tiny; after a few boxes, so do directions
// that move linearly with t (primitives that stay close and parallel while they turn: ccd.cpp).
// Boxes are bisected depth first,
// earlier t first (of a split in u or v, the half whose earliest face lies nearer 0 first),
// after their start has been advanced past any earliest part a direction shows apart; a
// box whose whole widened range lies within the tolerance cube [-δ, δ]^3, or one point of
// whose earliest face is certified within it, is a hit, and the reported TOI is the smallest
// lower t of the hits (boxes that start later than the best hit so far are dropped
// unexamined).
//
// Guarantee (no false negatives): if the primitives touch at some time t* in [0, 1]
// (including contact at t = 0 or t = 1, coplanar and parallel motion, degenerate triangles and
// edges, no motion), the result is {collides = true, toi <= t*}. The reverse does not hold: a
// pair whose primitives come within δ_k along every axis k at the same time (and same
// parameters) may be reported too, as may a pair whose search hits the box limit
// (CcdResult::hit_limit); those are the false positives.
//
// Tolerance: δ_k = max(kCcdRelativeTolerance * S, 8 ε_k), S the largest extent along an axis
// of the 8 input points, ε_k = 2^-47 * (largest |coordinate k| of the 8 points) + 2^-1060.
// Inputs must be finite with magnitudes below 2^1000; a non-finite input is reported as a
// collision at t = 0 (conservative).
#include "core/types.hpp"

#include <array>
#include <cstdint>

namespace vproxq {

/// δ relative to the extent of a query (see above).
inline constexpr double kCcdRelativeTolerance = 1e-6;
/// Boxes evaluated at most per query; past it the query is reported as colliding at the
/// smallest lower t of the boxes left and the hits so far (conservative). Degenerate
/// near-misses (parallel sliding just outside δ) are what can reach it. A box that can be
/// neither excluded nor split (sides of 2^-50) is counted as a hit the same way.
inline constexpr std::uint32_t kCcdMaxBoxes = 1u << 17;

struct CcdResult {
  bool collides = false;
  /// Earliest time of impact, a lower bound of the true one (only meaningful if collides).
  double toi = 1;
  bool hit_limit = false;     ///< reported because the box limit was reached
  std::uint32_t boxes = 0;    ///< parameter boxes evaluated (work counter)
};

/// A vertex against a triangle. start = {p, a, b, c} at t = 0, end = the same points at t = 1;
/// (a, b, c) is the triangle. Exact semantics: is there t in [0,1] where p(t) lies in the
/// closed triangle (a(t), b(t), c(t))? Conservative, see the header comment.
CcdResult vertex_face_ccd(const std::array<Vec3, 4>& start, const std::array<Vec3, 4>& end);

/// An edge (a0, a1) against an edge (b0, b1). start = {a0, a1, b0, b1} at t = 0, end at
/// t = 1. Exact semantics: is there t in [0,1] where the closed segments intersect?
CcdResult edge_edge_ccd(const std::array<Vec3, 4>& start, const std::array<Vec3, 4>& end);

/// The largest δ_k any query whose 8 points lie in a box of extent `extent` (largest side)
/// with coordinates bounded by `magnitude` can use: the pipeline widens its culling volumes by
/// it so that culling never removes a pair the kernel would report within δ.
double ccd_max_tolerance(double extent, double magnitude);

/// A share of ccd_max_tolerance() per point set, for culling by widened boxes: for two point
/// sets A and B (largest box sides sA, sB, coordinates bounded by mA, mB) whose boxes are at
/// most M apart along every axis, where M = ccd_max_tolerance(extent of A and B together,
/// max(mA, mB)) + R(max(mA, mB)) and R is a rounding slack that grows at most linearly with
/// the magnitude (R(max(x, y)) <= R(x) + R(y)): M <= ccd_tolerance_share(sA, mA) +
/// R(mA) * ccd_share_factor() + (the same for B). The extent of both together is at most
/// sA + sB + M; solving for M gives the factor.
double ccd_tolerance_share(double extent, double magnitude);
/// 1 / (1 - 2 kCcdRelativeTolerance): see ccd_tolerance_share().
double ccd_share_factor();

}  // namespace vproxq
