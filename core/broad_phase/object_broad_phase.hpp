#pragma once
// Stage I (paper 5.1): object AABBs, sorted intervals per axis, a conservative upper bound on
// each object's separation distance, and the object-level potentially neighbouring sets (PNS).
#include "core/broad_phase/aabb.hpp"
#include "core/broad_phase/triangle_bvh.hpp"
#include "core/parallel.hpp"
#include "core/scene.hpp"

#include <memory>
#include <mutex>
#include <utility>
#include <vector>

namespace vproxq {

/// A BVH over the boxes of a set of objects: leaf t is object ids[t].
struct ObjectBoxTree {
  std::vector<Index> ids;  ///< their boxes must not be empty
  TriangleBvh bvh;

  /// Over boxes[i] for i in `ids`.
  static ObjectBoxTree build(const std::vector<AABB>& boxes, std::vector<Index> ids);
};

/// Triangle and object boxes of one frame, computed once and shared by the stages.
struct FrameBoxes {
  std::vector<std::vector<AABB>> triangles;  ///< [object][triangle]
  std::vector<AABB> objects;                 ///< empty box for an object without triangles
  double magnitude = 0;                      ///< largest |coordinate| of any triangle corner
  std::vector<double> magnitudes;            ///< the same per object (0 without triangles)

  static FrameBoxes compute(const Frame& frame, int threads);

  /// Object i's BVH over triangles[i], built on first use (safe from several threads at once)
  /// and then shared by every query of the frame, and by copies of this FrameBoxes.
  const TriangleBvh& bvh(std::size_t i) const;
  /// Builds the BVHs of the objects for which want(i) holds, on `threads` threads: those of
  /// at least kLargeBvh triangles one after the other, each on all threads (a scene of one big
  /// cloth kept one thread busy), then the others in parallel, each on one.
  template <typename Want>
  void build_bvhs(int threads, const Want& want) const;
  static constexpr std::size_t kLargeBvh = 4096;
  /// The BVH of the boxes of the objects with triangles, built on first use (like bvh()).
  const ObjectBoxTree& object_tree() const;
  /// Object i's projections onto the diagonals, per triangle and per node of bvh(i) (frame:
  /// the frame these boxes are of), computed on first use (like bvh()) and then shared by the
  /// inter- and intra-object distance.
  const HierarchyDiagonals& diagonals(const Frame& frame, std::size_t i) const;

  struct BvhCache;
  std::shared_ptr<BvhCache> bvh_cache;  ///< set by compute()
};

/// Per object, a ball and a hollow around its box's centre c: every point of its triangles
/// lies within `outer` of c, and none within `inner` of c (the smallest distance from c to a
/// triangle). See enclosure_lower_bound().
struct Enclosure {
  Vec3 center = Vec3::Zero();
  double outer = 0, inner = 0;
};

struct FrameBoxes::BvhCache {
  explicit BvhCache(std::size_t n)
      : once(n), bvhs(n), enclosure_once(n), enclosures(n), diagonals_once(n), diagonals(n) {}
  std::vector<std::once_flag> once;
  std::vector<TriangleBvh> bvhs;
  std::once_flag object_once;
  ObjectBoxTree object_tree;
  /// Computed on first use (enclosure_lower_bound()): only pairs whose boxes overlap need them.
  std::vector<std::once_flag> enclosure_once;
  std::vector<Enclosure> enclosures;
  std::vector<std::once_flag> diagonals_once;
  std::vector<HierarchyDiagonals> diagonals;
};

inline const TriangleBvh& FrameBoxes::bvh(std::size_t i) const {
  std::call_once(bvh_cache->once[i], [&] { bvh_cache->bvhs[i].build(triangles[i]); });
  return bvh_cache->bvhs[i];
}

inline const HierarchyDiagonals& FrameBoxes::diagonals(const Frame& frame, std::size_t i) const {
  std::call_once(bvh_cache->diagonals_once[i], [&] {
    HierarchyDiagonals& d = bvh_cache->diagonals[i];
    d.triangles = triangle_diagonals(frame.objects[i]);
    d.nodes = node_diagonals(bvh(i), d.triangles);
  });
  return bvh_cache->diagonals[i];
}

template <typename Want>
void FrameBoxes::build_bvhs(int threads, const Want& want) const {
  for (std::size_t i = 0; i < triangles.size(); ++i)
    if (triangles[i].size() >= kLargeBvh && want(i))
      std::call_once(bvh_cache->once[i], [&] { bvh_cache->bvhs[i].build(triangles[i], threads); });
  parallel_for(triangles.size(), threads, [&](std::size_t i) {
    if (want(i)) bvh(i);
  });
}

struct ObjectBroadPhase {
  /// U_i: the distance from object i to some other object is at most this (kInfinity when
  /// no other object has triangles).
  std::vector<double> upper_bound;
  /// PNS(i): objects j != i whose box lies within upper_bound[i] (+ rounding slack) of i's
  /// box, sorted by box distance, then id. Every object at distance <= U_i is in it.
  std::vector<std::vector<Index>> pns;
};

/// Absolute slack added to bounds before culling, so that rounding in box distances and in
/// triangle_distance() can never cull a pair whose computed distance ties the bound.
/// triangle_distance() loses at most a few hundred ulps of the coordinate magnitude; this
/// allows ~4.5e5 ulps, so the only cost of its size is a handful of extra exact tests. It is
/// relative to `magnitude` (the largest coordinate magnitude), plus 2^-500 for underflow, so
/// it scales with the scene.
double rounding_slack(double magnitude);

/// A lower bound on the distance between objects i and j from their enclosures (Enclosure,
/// computed once per object and frame on first use): when i lies in j's hollow, every point of
/// i is within |c_i - c_j| + outer_i of c_j and every point of j at least inner_j from it, so
/// d(i, j) >= inner_j - |c_i - c_j| - outer_i (and the same the other way round). Nested
/// shells, or anything inside a closed surface, have boxes that contain each other: box
/// distances are 0 between all of them, this is not. Widened down by the rounding slack of
/// the two objects' coordinates; 0 when it says nothing. Callers use it for pairs whose boxes
/// overlap (elsewhere the box distance is the better bound, and the enclosures cost one
/// point-triangle distance per triangle).
double enclosure_lower_bound(const Frame& frame, const FrameBoxes& boxes, Index i, Index j);

/// The paper's rule: along each axis, the object whose interval overlaps i's the most (or the
/// nearest interval when none overlaps) is a potentially closest object. To those we add the
/// object whose box's farthest corner is nearest (found through a hierarchy of the object
/// boxes): the axis rule alone can pick objects that are far away along the other axes. U_i is
/// the smallest upper bound over these candidates, each bound being the smaller of the
/// farthest-corner box distance and the distance of a vertex pair found by a short
/// nearest-vertex walk. The PNS comes from the same hierarchy. O(n log n) in the number of
/// objects, plus the walks (linear in the candidates' triangles).
ObjectBroadPhase object_broad_phase(const Frame& frame, const FrameBoxes& boxes, int threads);

/// Pairs (a, b), a < b, of the objects of `tree` (built over `boxes`) whose boxes overlap
/// (boxes_overlap(): closed boxes, touching included), ascending. Through the hierarchy, in
/// parallel: a sweep along one axis costs the number of boxes sharing a slab of that axis,
/// which in a crowd grows with the square of the count.
std::vector<std::pair<Index, Index>> overlapping_box_pairs(const ObjectBoxTree& tree, const std::vector<AABB>& boxes,
                                                           int threads);

}  // namespace vproxq
