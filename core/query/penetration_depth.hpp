#pragma once
// Local penetration depth (paper 3.3, 6.1): for every pair of intersecting objects, the
// features of each inside the other (a local walk from the intersecting triangles), the
// penetration direction T (the closest-feature pair of maximal distance among them) and the
// depth (the width of the overlapping features projected on T).
#include "core/broad_phase/object_broad_phase.hpp"
#include "core/results.hpp"
#include "core/scene.hpp"

#include <vector>

namespace vproxq {

struct PenetrationDepthOptions {
  int threads = 1;  ///< worker threads (>= 1); the result does not depend on it
};

struct PenetrationDepthOutput {
  std::vector<PenetrationDepth> pairs;  ///< one per object pair in `intersecting`, ascending
  double ms = 0;
};

/// Computes the local PD of every object pair that has intersecting triangles, from the
/// sorted list `intersecting` (intersecting_pairs()). How (docs/algorithms.md, "Local penetration depth"):
///  1. Both objects must be closed, manifold and consistently oriented (each edge used by
///     exactly two faces, once in each direction), else the status says which it is not:
///     the inside test needs a well-defined interior.
///  2. Overlapping features of A (likewise B): starting from the vertices of A's intersecting
///     triangles, a walk over A's edges visits vertices while they lie inside B; "inside" is a
///     winding number != 0, computed exactly by counting the signed crossings of B along a
///     ray from the vertex in +x (orientation predicates, with a symbolic perturbation of the
///     ray so that crossings through B's edges and vertices count once). A walk that never
///     meets an outside vertex has swallowed a whole part of A: status too_deep.
///  3. T: for every inside vertex, its nearest point on the other object (point–triangle
///     distance through the other object's BVH); the pair of maximal distance gives T, as the
///     translation of objects[0] that brings that vertex (or its nearest point) back out.
///     When no vertex lies strictly inside (every such distance is 0: faces lying on each
///     other, or an overlap thinner than the mesh's edges), T is instead the unit normal of an
///     overlapping triangle along which the points of step 4 are narrowest (pointing out of
///     objects[1]); deepest_vertex is then kNoIndex. Status shallow only when no overlapping
///     triangle has a normal (all degenerate).
///  4. Depth: max - min of the projections on T of the inside vertices of both objects and of
///     the vertices of the intersection segments/polygons of the intersecting triangle pairs
///     (together, the vertices of the overlap region's boundary near the contact).
/// Self-intersections (pairs of one object, entry objects = [i, i]): the same steps within
/// the object, per contact (connected set of its intersecting pairs). "Inside" is the exact
/// winding number of the object's own surface on the vertex's outward side (a symbolic point
/// inside one of its faces, next to it) differing from its single-sheet value; T's nearest
/// point is taken outside the vertex's own sheet, bounded by the intersection curve; the
/// entry is the deepest contact. Status self_intersection only where that cannot be decided
/// (penetration_depth.cpp, "Self-intersections", and docs/algorithms.md).
PenetrationDepthOutput penetration_depth(const Frame& frame, const FrameBoxes& boxes,
                                         const std::vector<IntersectingPair>& intersecting,
                                         const PenetrationDepthOptions& opts);

/// Signed number of times the surface of `object` winds around p: +1 inside a closed,
/// consistently outward-oriented surface, -1 inside an inward-oriented one, 0 outside (the
/// exact count of signed crossings of a ray from p in +x, see above). Sets on_surface (and
/// returns 0) when p lies on a (closed) face of the surface. Brute force over all triangles:
/// the reference for the BVH-accelerated version used by penetration_depth().
int winding_number_brute_force(const Vec3& p, const Object& object, bool& on_surface);

}  // namespace vproxq
