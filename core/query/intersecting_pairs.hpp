#pragma once
// Discrete collision detection (paper 3.2): every intersecting triangle pair of a frame,
// between objects and within an object (pairs sharing no vertex), decided with the exact
// triangle–triangle intersection test.
#include "core/broad_phase/object_broad_phase.hpp"
#include "core/results.hpp"
#include "core/scene.hpp"

#include <vector>

namespace vproxq {

struct VoronoiBounds;

struct IntersectingPairsOptions {
  int threads = 1;  ///< worker threads (>= 1); the result does not depend on it
  /// Stage II's bounds for this frame, or null. A triangle f with D_l(f) > 0 is at positive
  /// distance from every other object, so it is skipped in the inter-object search; the
  /// intra-object search does not use them (D_l is a distance to other objects).
  const VoronoiBounds* voronoi = nullptr;
  bool intra = true;  ///< also list pairs within one object
  /// Per object, its exact distance to the nearest other object (the inter-object distance's
  /// answers, InterObjectDistance::distance), or null. An object at positive distance from
  /// all others intersects none of them, so object pairs with such an object are skipped.
  const std::vector<double>* object_distance = nullptr;
  /// With `intra`: the pairs within objects that the intra-object distance already found
  /// (IntraDistanceOutput::intersecting), all those of every object but the ones its `skip`
  /// left out (`intra_skip`, the same mask, may be null). Those objects are not searched
  /// again, and their pairs join the output as given. Null: search every object.
  const std::vector<IntersectingPair>* intra_pairs = nullptr;
  const std::vector<std::uint8_t>* intra_skip = nullptr;
};

struct IntersectingPairsOutput {
  std::vector<IntersectingPair> pairs;  ///< sorted (IntersectingPair::operator<), no duplicates
  std::uint64_t exact_tests = 0;        ///< exact triangle–triangle intersection tests run (not
                                        ///< those behind `intra_pairs`)
  double ms = 0;
};

/// Object pairs with overlapping boxes (sweep and prune along x), triangles of one object
/// whose boxes overlap the other's object box, their overlapping triangle boxes in the other
/// object's BVH, then the exact test; within an object, the BVH's self-overlaps minus the
/// pairs sharing a vertex. Touching counts as intersecting.
IntersectingPairsOutput intersecting_pairs(const Frame& frame, const FrameBoxes& boxes,
                                           const IntersectingPairsOptions& opts);
IntersectingPairsOutput intersecting_pairs(const Frame& frame, const IntersectingPairsOptions& opts);

/// Every triangle pair tested, no culling: the reference for tests.
IntersectingPairsOutput intersecting_pairs_brute_force(const Frame& frame, bool intra = true);

}  // namespace vproxq
