#pragma once
// Triangle–cube overlap (separating axis test), used for conservative voxelization; and a
// conservative test of a box against a triangle's plane, used by the intersecting-pairs search.
#include "core/broad_phase/aabb.hpp"
#include "core/types.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <utility>

namespace vproxq {

/// The separating-axis test of one triangle against axis-aligned cubes of one half side: the
/// 13 axes (3 box normals, the triangle normal, 9 edge cross products) and the triangle's
/// extent along each, widened by the cube's reach, are computed once, so a cube costs one dot
/// product per axis.
///
/// Rounding: a cube is reported separated along axis a when its centre's projection a·c lies
/// outside [min_i a·v_i - r, max_i a·v_i + r], r = half * |a|_1, all in double. Each of these
/// numbers is off by a few ulps of |a|_1 * M, M the largest coordinate magnitude involved, so
/// callers that need a conservative answer (every cube the exact triangle touches reported)
/// pass a half side widened by a slack well above 2^-50 * M (StageGrid uses 1e-9 * M). Any
/// axis is a valid separating direction, so the rounding of the axes themselves is harmless.
class TriangleBoxTester {
 public:
  TriangleBoxTester(const Triangle& t, double half);

  /// True unless one of the 13 axes separates the triangle from the cube centred at `center`.
  bool overlaps(const Vec3& center) const {
    for (size_t a = 0; a < kAxes; ++a) {
      const double s = axis_[a].dot(center);
      if (s < lo_[a] || s > hi_[a]) return false;
    }
    return true;
  }

  /// On the row of cubes centred at (x, cy, cz), an interval [lo, hi] of x (lo > hi: empty)
  /// outside which overlaps() is false. `magnitude` bounds every |coordinate| of the centres
  /// and of the triangle. Each axis a bounds a.x * x to [lo_a - t, hi_a - t], t = a.y cy + a.z cz,
  /// widened by 2^-40 (|a|_1 magnitude + |lo_a| + |hi_a|), far above the few ulps by which
  /// overlaps()'s a · c and this t + a.x x can differ; an axis with a.x = 0 accepts or rejects
  /// the whole row. The divisions round the interval's ends by an ulp of themselves: callers
  /// widen it by a cube (voxelize_cells()).
  std::pair<double, double> row_span(double cy, double cz, double magnitude) const {
    double lo = -std::numeric_limits<double>::infinity(), hi = std::numeric_limits<double>::infinity();
    for (size_t a = 0; a < kAxes; ++a) {
      const Vec3& ax = axis_[a];
      const double t = ax.y() * cy + ax.z() * cz;
      const double m = 0x1p-40 * ((std::abs(ax.x()) + std::abs(ax.y()) + std::abs(ax.z())) * magnitude +
                                  std::abs(lo_[a]) + std::abs(hi_[a]));
      const double l = lo_[a] - t - m, h = hi_[a] - t + m;
      if (ax.x() == 0) {
        if (l > 0 || h < 0) return {1, 0};
      } else if (ax.x() > 0) {
        lo = std::max(lo, l / ax.x());
        hi = std::min(hi, h / ax.x());
      } else {
        lo = std::max(lo, h / ax.x());
        hi = std::min(hi, l / ax.x());
      }
    }
    return {lo, hi};
  }

 private:
  static constexpr size_t kAxes = 13;
  std::array<Vec3, kAxes> axis_;
  std::array<double, kAxes> lo_, hi_;  // projections' range, widened by the cube's reach
};

/// Whether a box lies strictly on one side of a triangle's plane, so that no triangle inside
/// it can touch the triangle (a common point would lie on that plane). A long sliver crossing
/// a fine mesh has a box over a large part of it; this keeps the intersecting-pairs search to
/// the BVH nodes its plane cuts (50 slivers across a 180,000-triangle sheet: 3.1 M triangle
/// tests before).
///
/// Rounding (u = 2^-53; M the largest |coordinate| of the triangle and the box; L the largest
/// |component| of the triangle's two computed edges b - a, c - a): each edge component is
/// within u of itself relatively, so the computed normal n̂ is within 10uL^2 of the exact one
/// per component; the box's centre and half sides are within uM; the centre minus a within
/// 3uM. The computed signed distance of the centre, n̂ . (m - a), is then within
/// 60.3uL^2 M + 9.1u|n̂|_1 M of the exact one, and the spread Σ|n̂_k| h_k within
/// 30uL^2 M + 4.1u|n̂|_1 M (each dot product adds γ3 = 3.01u of its terms). Their sum is below
/// E = 2^-46 M (L^2 + |n̂|_1) (2^-46 = 128u), also after the rounding of E and of d ± r.
/// A degenerate triangle (exact normal 0) never rejects: its computed values stay below E.
/// Nonzero coordinates are at least 2^-200 in magnitude (types.hpp), so nothing here
/// underflows; an overflow makes E or the values infinite or NaN, which never rejects.
class TrianglePlane {
 public:
  explicit TrianglePlane(const Triangle& t) : a(t[0]) {
    const Vec3 e1 = t[1] - t[0], e2 = t[2] - t[0];
    n = e1.cross(e2);
    const double l = std::max(e1.cwiseAbs().maxCoeff(), e2.cwiseAbs().maxCoeff());
    scale = l * l + n.cwiseAbs().sum();
    m = std::max({t[0].cwiseAbs().maxCoeff(), t[1].cwiseAbs().maxCoeff(), t[2].cwiseAbs().maxCoeff()});
  }

  /// True only if the closed box lies strictly on one side of the triangle's plane.
  bool rejects(const AABB& box) const {
    const double mm = std::max({m, box.lo.cwiseAbs().maxCoeff(), box.hi.cwiseAbs().maxCoeff()});
    const double e = 0x1p-46 * mm * scale;
    const Vec3 centre = 0.5 * (box.lo + box.hi), half = 0.5 * (box.hi - box.lo);
    const double d = n.dot(centre - a);
    const double r = n.cwiseAbs().dot(half);
    return d - r > e || d + r < -e;
  }

 private:
  Vec3 a, n;
  double scale = 0;  ///< L^2 + |n̂|_1 (above)
  double m = 0;      ///< the triangle's largest |coordinate|
};

}  // namespace vproxq
