#include "core/voronoi/grid_setup.hpp"

namespace vproxq {

std::vector<std::int64_t> fill_dvd_triangles(DvdInput& in, const Frame& frame, const StageGrid& sg) {
  const size_t n = frame.objects.size();
  std::vector<std::int64_t> tri_base(n + 1, 0);
  for (size_t i = 0; i < n; ++i) tri_base[i + 1] = tri_base[i] + frame.objects[i].num_triangles();
  in.tri_xyz.resize(static_cast<size_t>(tri_base[n]) * 9);
  in.tri_xyz_d.resize(in.tri_xyz.size());
  in.tri_site.resize(static_cast<size_t>(tri_base[n]));
  for (size_t i = 0; i < n; ++i) {
    const Object& o = frame.objects[i];
    for (Index t = 0; t < o.num_triangles(); ++t) {
      const size_t g = static_cast<size_t>(tri_base[i] + t);
      const Triangle tri = o.triangle(t);
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) {
          const double v = (tri[static_cast<size_t>(c)][k] - sg.grid.origin[k]) / sg.unit;
          in.tri_xyz_d[g * 9 + static_cast<size_t>(c * 3 + k)] = v;
          in.tri_xyz[g * 9 + static_cast<size_t>(c * 3 + k)] = static_cast<float>(v);
        }
      in.tri_site[g] = static_cast<std::int32_t>(i);
    }
  }
  return tri_base;
}

}  // namespace vproxq
