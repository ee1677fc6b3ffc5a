#pragma once
// Intra-object ("self") distance (paper 3, 5.2.2, fig. 3): for every triangle f of every object,
// its nearest triangle of the same object that shares no vertex with f (f's 1-ring and f itself
// are its adjacent features and are excluded), and per object the minimum.
#include "core/broad_phase/object_broad_phase.hpp"
#include "core/results.hpp"
#include "core/scene.hpp"

#include <cstdint>
#include <vector>

namespace vproxq {

struct SelfVoronoiBounds;

/// Per object and triangle, an upper bound of the triangle's intra-object distance from its
/// 2-ring (paper 5.2.2): the smallest distance between a vertex of f and a vertex of a 2-ring
/// triangle (2-ring triangles share no vertex with f, so each is a valid non-adjacent
/// candidate, and a vertex pair's distance bounds the triangle pair's). kInfinity when the
/// 2-ring is empty. Cheap (no triangle–triangle tests): the 2-ring triangles are tested in
/// Stage III like any other candidate, only when they survive culling.
///
/// The 2-ring's vertices come from Adjacency::ring2_vertices(), a walk from f's vertices to
/// the 1-ring's other vertices and their triangles that skips vertices used by more than 64
/// triangles (Adjacency::kRingWalkValence; as a vertex of f or of the 1-ring): the
/// triangles around such a hub are all in each other's 1-rings, and walking through it would
/// cost of the order of its valence squared. Where a hub is skipped the bound comes
/// from the part of the 2-ring reached without it (larger, or kInfinity), which is still an
/// upper bound; where no vertex of valence above 64 is near f, it is the whole 2-ring's.
/// With `skip`, objects it marks (1) are left out: their bounds stay kInfinity.
std::vector<std::vector<double>> ring2_upper_bounds(const Frame& frame, int threads,
                                                    const std::vector<std::uint8_t>* skip = nullptr);

struct IntraDistanceOptions {
  int threads = 1;  ///< worker threads for Stage III (>= 1)
  /// Stage II's per-triangle bounds (D_u, D_l) for this frame, or null for AABB-only culling.
  /// They change which pairs are tested, never the answer.
  const SelfVoronoiBounds* voronoi = nullptr;
  /// Per object, 1 to leave it out (its result has its object id and nothing else): for a
  /// caller that has its result already. An object's result depends on that object alone.
  const std::vector<std::uint8_t>* skip = nullptr;
};

struct IntraDistanceOutput {
  std::vector<IntraObjectDistance> per_object;  ///< indexed by object id
  DistanceCounters counters;                    ///< the intra_* fields
  double exact_ms = 0;                          ///< BVHs, candidates and exact tests
  /// Every intersecting pair of triangles sharing no vertex within each object not left out
  /// by `skip`, sorted, once each: the exact tests meet every such pair (see
  /// intra_object_distance()), so the intersecting pairs need not search for them again.
  std::vector<IntersectingPair> intersecting;
};

/// Stage III of the intra-object query. Per object, its BVH is descended against itself
/// (TriangleBvh::descend_self()), entering a pair of subtrees when a triangle of one may need a
/// triangle of the other: their boxes within the first one's largest bound (D_u + rounding
/// slack, D_u the 2-ring bound or Stage II's when smaller) and, with Stage II, the other's
/// smallest D_l within it too; and not when a vertex is common to all their triangles. Each
/// unordered pair of non-adjacent triangles of two entered leaves is a candidate for f when
/// their boxes lie within f's bound min(D_u(f), f's best so far) + slack and D_l(g) does too
/// (likewise for g); a side whose bound the pair's separation bound exceeds drops it, and a
/// pair still wanted by either side is evaluated once and offered to both (SharedPairs).
/// Within a unit of work (a node pair of at most 256 triangles), pairs whose boxes overlap are
/// tried as the descent meets them and the others after it, nearer boxes first.
///
/// Every non-adjacent pair that intersects (distance 0) is evaluated: its boxes overlap, its
/// separation bound is at most 0 and both D_l are at most 0, so no bound culls it. Those
/// evaluated as intersecting are listed in `intersecting`, once each.
///
/// Deterministic and thread-count independent: every unordered pair {f, g} is evaluated as
/// triangle_distance(triangle min(f, g), triangle max(f, g)) (points swapped for the other
/// side), f's answer is the smallest (distance, g) and the object's the smallest
/// (distance, f, g): bitwise the brute force's. `ring2_bound` is ring2_upper_bounds(frame).
IntraDistanceOutput intra_object_distance(const Frame& frame, const FrameBoxes& boxes,
                                          const std::vector<std::vector<double>>& ring2_bound,
                                          const IntraDistanceOptions& opts);

/// The same, computing the boxes and the 2-ring bounds itself.
IntraDistanceOutput intra_object_distance(const Frame& frame, const IntraDistanceOptions& opts);

/// All non-adjacent pairs of every object, no culling: the reference for tests. `threads`
/// splits the triangles of an object (each triangle's scan stays sequential).
IntraDistanceOutput intra_object_distance_brute_force(const Frame& frame, int threads = 1);

/// A second reference for meshes too large for the brute force (tests on the bunny, the height
/// field): for each f, every other triangle in order of its box's distance from f's box, exact
/// tests until that box distance exceeds the best distance found (+ rounding slack). Nothing
/// shared with the query (no BVH, no bounds, no Stage II); the same pairs, canonical evaluation
/// and tie-break as the brute force, so its results are bitwise the brute force's (tested).
IntraDistanceOutput intra_object_distance_sorted_scan(const Frame& frame, int threads = 1);

}  // namespace vproxq
