#pragma once
// Triangle–cube overlap (separating axis test), used for conservative voxelization.
#include "core/types.hpp"

#include <array>

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

 private:
  static constexpr size_t kAxes = 13;
  std::array<Vec3, kAxes> axis_;
  std::array<double, kAxes> lo_, hi_;  // projections' range, widened by the cube's reach
};

}  // namespace vproxq
