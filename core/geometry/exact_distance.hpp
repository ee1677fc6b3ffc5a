#pragma once
// Exact squared point-triangle distances, to decide what double precision cannot: which of
// two distances is smaller when they are equal or within rounding of each other (penetration
// depth's deepest vertex and its nearest face, docs/algorithms.md, "Local penetration depth"). Every double
// is a dyadic rational m * 2^k, and so is every sum, difference and product of them; the
// squared distance is a quotient of two such numbers. They are computed here in arbitrary
// precision: double expansions would overflow, since the coordinates reach 2^200 and a
// comparison multiplies ten coordinate differences. Slow (allocations, schoolbook products):
// for the rare near ties only.
#include <cstdint>
#include <vector>

#include "core/types.hpp"

namespace vproxq {

/// An exact dyadic number: magnitude * 2^exponent, with a sign.
class Dyadic {
 public:
  Dyadic() = default;  ///< zero
  explicit Dyadic(double x);  ///< x finite
  int sign() const { return magnitude_.empty() ? 0 : (negative_ ? -1 : 1); }
  Dyadic operator-() const;
  friend Dyadic operator+(const Dyadic& a, const Dyadic& b);
  friend Dyadic operator-(const Dyadic& a, const Dyadic& b);
  friend Dyadic operator*(const Dyadic& a, const Dyadic& b);
  /// sign(a - b).
  friend int compare(const Dyadic& a, const Dyadic& b);

 private:
  bool negative_ = false;
  std::vector<std::uint32_t> magnitude_;  ///< little-endian base 2^32; no zero limb at either end
  std::int64_t exponent_ = 0;             ///< of the lowest limb's lowest bit
  void normalize();
};

/// num / den with den > 0.
struct ExactFraction {
  Dyadic num;
  Dyadic den;
};

/// sign(a - b).
int compare(const ExactFraction& a, const ExactFraction& b);

/// The exact squared distance from p to the closed triangle t, for any triangle (degenerate
/// ones are the union of their edges): the smallest of the squared distances to the corners,
/// to the edges' lines where the foot lies inside the edge, and to the plane where the
/// projection lies inside the triangle, each one a point of the triangle.
ExactFraction exact_point_triangle_squared_distance(const Vec3& p, const Triangle& t);

}  // namespace vproxq
