#include "core/geometry/triangle_box.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace vproxq {
namespace {

/// Does axis `a` separate the triangle (corners v, relative to the box centre) from the box?
bool separates(const Vec3& a, const Vec3 v[3], double half) {
  const double p0 = a.dot(v[0]), p1 = a.dot(v[1]), p2 = a.dot(v[2]);
  const double r = half * (std::abs(a.x()) + std::abs(a.y()) + std::abs(a.z()));
  return std::min({p0, p1, p2}) > r || std::max({p0, p1, p2}) < -r;
}

}  // namespace

bool triangle_box_overlap(const Triangle& t, const Vec3& center, double half) {
  const Vec3 v[3] = {t[0] - center, t[1] - center, t[2] - center};
  for (int k = 0; k < 3; ++k) {
    const double lo = std::min({v[0][k], v[1][k], v[2][k]});
    const double hi = std::max({v[0][k], v[1][k], v[2][k]});
    if (lo > half || hi < -half) return false;
  }
  const Vec3 e[3] = {v[1] - v[0], v[2] - v[1], v[0] - v[2]};
  const Vec3 n = e[0].cross(e[1]);
  if (separates(n, v, half)) return false;
  for (const Vec3& edge : e)
    for (int k = 0; k < 3; ++k) {
      const Vec3 axis = Vec3(Vec3::Unit(k)).cross(edge);
      if (separates(axis, v, half)) return false;
    }
  return true;
}

}  // namespace vproxq
