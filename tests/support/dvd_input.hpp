#pragma once
// Reading DvdInput back in the Voronoi backend tests (CPU and GL suites).
#include "core/voronoi/cpu_gather.hpp"

namespace vproxq::test {

/// Triangle t of the input, in the input's (origin-relative) double coordinates.
inline Triangle triangle_of(const DvdInput& in, std::size_t t) {
  const double* c = &in.tri_xyz_d[9 * t];
  return {Vec3(c[0], c[1], c[2]), Vec3(c[3], c[4], c[5]), Vec3(c[6], c[7], c[8])};
}

/// Centre of voxel `id`, relative to the grid origin, computed as the backends do
/// (cell * (index + 0.5); VoronoiGrid::center() adds and removes the origin, which rounds).
inline Vec3 sample_point(const VoronoiGrid& grid, std::int64_t id) { return voxel_centre(grid, id); }

}  // namespace vproxq::test
