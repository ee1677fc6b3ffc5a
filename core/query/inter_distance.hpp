#pragma once
// N-body inter-object distance: for every object, its nearest other object (paper 3.1, 5.1, 5.3).
#include "core/broad_phase/object_broad_phase.hpp"
#include "core/results.hpp"
#include "core/scene.hpp"

#include <vector>

namespace vproxq {

struct VoronoiBounds;

struct InterDistanceOptions {
  int threads = 1;  ///< worker threads for Stage III (>= 1)
  /// Stage II's bounds (D_u per object, D_l per triangle) for this frame, or null for
  /// AABB-only culling. They change which pairs are tested, never the answer.
  const VoronoiBounds* voronoi = nullptr;
};

struct InterDistanceOutput {
  std::vector<InterObjectDistance> per_object;  ///< indexed by object id
  DistanceCounters counters;
  double aabb_ms = 0;   ///< Stage I (object AABBs, sweep and prune, bounds, object PNS)
  double exact_ms = 0;  ///< feature-level candidates and exact tests
};

/// Stage I (AABB sweep-and-prune culling) then Stage III (exact tests on what is left).
/// Deterministic: the result does not depend on the thread count. For each object i the
/// answer is the lexicographically smallest (distance, nearest object, triangle on i,
/// triangle on the other) over all triangle pairs, where the pair of objects i < j is always
/// evaluated as triangle_distance(triangle of i, triangle of j) and points are swapped for j.
InterDistanceOutput inter_object_distance(const Frame& frame, const InterDistanceOptions& opts);

/// The same with Stage I already done by the caller (who ran Stage II in between).
InterDistanceOutput inter_object_distance(const Frame& frame, const FrameBoxes& boxes,
                                          const ObjectBroadPhase& stage1,
                                          const InterDistanceOptions& opts);

/// All triangle pairs of all object pairs, no culling: the reference for tests.
InterDistanceOutput inter_object_distance_brute_force(const Frame& frame);

}  // namespace vproxq
