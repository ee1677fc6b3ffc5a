#pragma once
// Reading DvdInput back in the Voronoi backend tests (CPU and GL suites).
#include "core/voronoi/discrete_voronoi.hpp"

namespace vproxq::test {

/// Triangle t of the input, in the input's (origin-relative) double coordinates.
inline Triangle triangle_of(const DvdInput& in, std::size_t t) {
  const double* c = &in.tri_xyz_d[9 * t];
  return {Vec3(c[0], c[1], c[2]), Vec3(c[3], c[4], c[5]), Vec3(c[6], c[7], c[8])};
}

/// Centre of voxel `id`, relative to the grid origin, computed as the backends do
/// (cell * (index + 0.5); VoronoiGrid::center() adds and removes the origin, which rounds).
inline Vec3 sample_point(const VoronoiGrid& grid, std::int64_t id) {
  const std::int64_t x = id % grid.dims[0];
  const std::int64_t y = (id / grid.dims[0]) % grid.dims[1];
  const std::int64_t z = id / (std::int64_t{grid.dims[0]} * grid.dims[1]);
  return grid.cell * Vec3(static_cast<double>(x) + 0.5, static_cast<double>(y) + 0.5,
                          static_cast<double>(z) + 0.5);
}

}  // namespace vproxq::test
