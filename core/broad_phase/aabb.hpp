#pragma once
// Axis-aligned bounding boxes and the distance bounds Stage I derives from them.
#include "core/types.hpp"

#include <algorithm>
#include <cmath>

namespace vproxq {

struct AABB {
  Vec3 lo = Vec3::Constant(kInfinity);
  Vec3 hi = Vec3::Constant(-kInfinity);

  bool empty() const { return lo.x() > hi.x(); }
  void extend(const Vec3& p) {
    lo = lo.cwiseMin(p);
    hi = hi.cwiseMax(p);
  }
  void extend(const AABB& b) {
    lo = lo.cwiseMin(b.lo);
    hi = hi.cwiseMax(b.hi);
  }
  Vec3 center() const { return 0.5 * (lo + hi); }
  static AABB of(const Triangle& t) {
    AABB b;
    b.lo = t[0].cwiseMin(t[1]).cwiseMin(t[2]);
    b.hi = t[0].cwiseMax(t[1]).cwiseMax(t[2]);
    return b;
  }
};

/// Whether the closed boxes a and b overlap (touching included): exact comparisons, and
/// cheaper than box_distance_squared() == 0, which a gap below ~1e-154 also passes (its
/// square underflows).
inline bool boxes_overlap(const AABB& a, const AABB& b) {
  return a.lo.x() <= b.hi.x() && b.lo.x() <= a.hi.x() && a.lo.y() <= b.hi.y() && b.lo.y() <= a.hi.y() &&
         a.lo.z() <= b.hi.z() && b.lo.z() <= a.hi.z();
}

/// Squared distance between two boxes (0 when they overlap): a lower bound for the squared
/// distance between anything inside them.
inline double box_distance_squared(const AABB& a, const AABB& b) {
  double s = 0;
  for (int k = 0; k < 3; ++k) {
    const double gap = std::max(a.lo[k] - b.hi[k], b.lo[k] - a.hi[k]);
    if (gap > 0) s += gap * gap;
  }
  return s;
}

/// Largest distance between a point of `a` and a point of `b` (between their farthest
/// corners): an upper bound for the distance between anything inside them (paper 5.1).
inline double box_max_distance(const AABB& a, const AABB& b) {
  double s = 0;
  for (int k = 0; k < 3; ++k) {
    const double w = std::max(a.hi[k] - b.lo[k], b.hi[k] - a.lo[k]);
    s += w * w;
  }
  return std::sqrt(s);
}

/// Length of the overlap of the projections of a and b on axis k (negative: the gap).
inline double interval_overlap(const AABB& a, const AABB& b, int k) {
  return std::min(a.hi[k], b.hi[k]) - std::max(a.lo[k], b.lo[k]);
}

}  // namespace vproxq
