#pragma once
// The unit-sphere mesh every blob is built from.
#include "core/types.hpp"
#include "sample_scenes/generators/det_math.hpp"

#include <vector>

namespace vproxq::gen {

/// A closed triangle mesh with all vertices on the unit sphere, faces oriented outwards.
struct UnitSphereMesh {
  std::vector<V3> directions;  ///< vertex positions, |d| = 1 (to rounding)
  std::vector<Face> faces;     ///< 0-based, counter-clockwise seen from outside
};

/// Class-I geodesic sphere: each of the icosahedron's 20 faces is cut into frequency^2
/// triangles on a regular grid, and the grid points are projected onto the sphere.
/// 20 f^2 triangles, 10 f^2 + 2 vertices (f = 1: the icosahedron; f = 3: 180 triangles;
/// f = 2^s: as many triangles as s levels of recursive midpoint subdivision, though the
/// vertices sit in slightly different places). Vertices on shared edges are shared, so the
/// mesh is closed and manifold. Requires frequency >= 1.
UnitSphereMesh geodesic_sphere(int frequency);

}  // namespace vproxq::gen
