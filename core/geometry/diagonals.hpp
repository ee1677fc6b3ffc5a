#pragma once
// Projections of point sets onto the four diagonals (1, ±1, ±1): with the axis-aligned box, a
// 14-sided hull. A layer of cloth lying aslant to the axes is boxed with the layers beside it;
// along the diagonal nearest its normal the two often come apart.
#include "core/types.hpp"

#include <algorithm>
#include <array>
#include <vector>

namespace vproxq {

/// A point set's projections onto the diagonals w = (1, ±1, ±1) (diagonal d: the signs of y
/// and z from bits 0 and 1), smallest and largest. Each projection is two rounded sums, off by
/// at most a few 2^-53 M (M the largest |coordinate|).
struct Diagonals {
  std::array<double, 4> lo{kInfinity, kInfinity, kInfinity, kInfinity};
  std::array<double, 4> hi{-kInfinity, -kInfinity, -kInfinity, -kInfinity};

  void extend(const Vec3& x) {
    for (size_t d = 0; d < 4; ++d) {
      const double p = (x[0] + ((d & 1) ? -x[1] : x[1])) + ((d & 2) ? -x[2] : x[2]);
      lo[d] = std::min(lo[d], p);
      hi[d] = std::max(hi[d], p);
    }
  }
  void extend(const Diagonals& o) {
    for (size_t d = 0; d < 4; ++d) {
      lo[d] = std::min(lo[d], o.lo[d]);
      hi[d] = std::max(hi[d], o.hi[d]);
    }
  }
};

/// Per node of a hierarchy (TriangleBvh), the Diagonals of its subtree's triangles, from each
/// triangle's (indexed by triangle id).
template <typename Bvh>
std::vector<Diagonals> node_diagonals(const Bvh& bvh, const std::vector<Diagonals>& per_triangle) {
  return bvh.fold_nodes(Diagonals{}, [&](Index t) { return per_triangle[static_cast<size_t>(t)]; },
                        [](Diagonals x, const Diagonals& y) {
                          x.extend(y);
                          return x;
                        });
}

/// Per triangle of an object (anything with num_triangles() and triangle(t)), the Diagonals
/// of its corners.
template <typename Obj>
std::vector<Diagonals> triangle_diagonals(const Obj& o) {
  std::vector<Diagonals> out(static_cast<size_t>(o.num_triangles()));
  for (Index t = 0; t < o.num_triangles(); ++t)
    for (const Vec3& x : o.triangle(t)) out[static_cast<size_t>(t)].extend(x);
  return out;
}

/// An object's Diagonals per triangle (by id) and per node of its hierarchy (node_diagonals()).
struct HierarchyDiagonals {
  std::vector<Diagonals> nodes;
  std::vector<Diagonals> triangles;
};

/// The largest gap between the projections of a and b onto one diagonal (0 when they overlap
/// on all four): divided by sqrt(3), a lower bound on the distance between the two sets (up
/// to the rounding above: callers compare it with a bound that carries a larger slack).
inline double diagonal_gap(const Diagonals& a, const Diagonals& b) {
  double gap = 0;
  for (size_t d = 0; d < 4; ++d) gap = std::max({gap, b.lo[d] - a.hi[d], a.lo[d] - b.hi[d]});
  return gap;
}

/// A squared lower bound `d2` on the distance between two sets (their boxes'), raised to the
/// square of the diagonal gap / sqrt(3) where that is larger.
inline double raised_distance_squared(double d2, const Diagonals& a, const Diagonals& b) {
  const double gap = diagonal_gap(a, b);
  return std::max(d2, gap * gap / 3);
}

}  // namespace vproxq
