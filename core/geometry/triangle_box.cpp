#include "core/geometry/triangle_box.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace vproxq {

TriangleBoxTester::TriangleBoxTester(const Triangle& t, double half) {
  const Vec3 e[3] = {t[1] - t[0], t[2] - t[1], t[0] - t[2]};
  size_t k = 0;
  for (int c = 0; c < 3; ++c) axis_[k++] = Vec3::Unit(c);
  axis_[k++] = e[0].cross(e[1]);
  for (const Vec3& edge : e)
    for (int c = 0; c < 3; ++c) axis_[k++] = Vec3(Vec3::Unit(c)).cross(edge);
  for (size_t a = 0; a < kAxes; ++a) {
    const Vec3& ax = axis_[a];
    const double p0 = ax.dot(t[0]), p1 = ax.dot(t[1]), p2 = ax.dot(t[2]);
    const double r = half * (std::abs(ax.x()) + std::abs(ax.y()) + std::abs(ax.z()));
    lo_[a] = std::min({p0, p1, p2}) - r;
    hi_[a] = std::max({p0, p1, p2}) + r;
  }
}

}  // namespace vproxq
