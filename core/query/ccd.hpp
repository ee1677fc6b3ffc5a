#pragma once
// Continuous collision detection between two frames (paper 3.2, 5.3): every vertex–face and
// edge–edge pair that collides while the vertices move linearly from frame k to frame k+1,
// inter-object and intra-object, with its earliest time of impact.
//
// Pipeline: objects are matched by position in the frames' lists (the CLI first reorders the
// next frame by name, and pieces of broken meshes by their vertices: ccd_counterparts()); an
// object whose counterpart is missing, whose topology differs, whose name is found at another
// position of the next frame (objects listed in another order) or, for a piece, whose
// counterpart holds other vertices, is skipped for the step (CcdStepResult::skipped).
// Stage I: swept boxes (the box of a triangle's 6 positions, widened by the culling margin
// below), sweep-and-prune over the swept object boxes, then per object pair a BVH over the
// swept triangle boxes gives the candidate triangle pairs; a subtree or a pair that a
// separating axis shows apart by more than twice the margin at both ends of the step (hence
// throughout it: ccd.cpp) is skipped (two triangles of one object sharing one vertex: when one
// axis through that vertex shows all their primitive pairs apart), and so is each primitive
// pair of the remaining triangle pairs that the same argument shows apart
// (CcdCounters::separated_primitives). Optional Stage II
// (core/voronoi/ccd_stage2.hpp) culls the inter-object triangle pairs left after the
// separating-axis tests (of the pairs and of their primitives) with a voxelization of the swept
// prisms: of those pairs' triangles only, when built here. Pairs within one object go from
// Stage I to Stage III (Stage II nearly never ruled one out: ccd.cpp).
// Stage III: the elementary tests of core/geometry/ccd.hpp, each vertex–face and edge–edge pair
// tested once (see ccd.cpp for the ownership rule that deduplicates without a global set).
//
// Exclusions: a vertex–face pair whose vertex is a corner of the face, and an edge–edge pair
// of one object sharing a vertex. Vertices used by no face take no part.
//
// Culling margin: the kernel may report a pair whose primitives come within its tolerance δ
// (never more than ccd_max_tolerance() for the coordinates of the query's 8 points, which lie
// among the 12 positions of the two triangles the pair comes from). Each triangle has a share
// of the margin from its own swept box (ccd_tolerance_share() plus rounding slack), and a
// triangle pair's margin is the sum of the two shares, or the object pair's margin
// (ccd_margin_between() of the objects' swept boxes) when smaller; a triangle against a BVH
// subtree uses the subtree's box's share. The primitive box tests widen by the margin, the
// separating-axis tests ask for twice that (the kernel's per-axis δ allows a Euclidean gap of
// sqrt(3) δ). Triangle boxes are widened by their own share, and Stage II by the step's
// largest margin, so culling never removes a pair the kernel would report and the results
// equal the brute force — with one documented exception: a
// test that stops at the kernel's box limit (counters.limit_hits) is reported without a
// proximity guarantee, so brute force could report such a pair where culling (correctly: it
// cannot collide) removed it.
#include "core/broad_phase/aabb.hpp"
#include "core/results.hpp"
#include "core/scene.hpp"

#include <optional>

namespace vproxq {

class CcdVoxelCulling;
class CcdVoxelBackend;

struct CcdOptions {
  int threads = 1;
  /// Stage II: culling by a conservative voxelization of the swept triangles, built by the
  /// caller for this step (ccd_stage2.hpp), or null. It never changes the answer.
  const CcdVoxelCulling* voxels = nullptr;
  /// Or, when `voxels` is null, Stage II built here with this backend after Stage I, over the
  /// triangles of the inter-object candidate pairs Stage I leaves (not shown apart, and with a
  /// primitive pair not shown apart: the only pairs whose keys are ever looked at); the result's
  /// voronoi_ms, voxel_grid, voxel_cell and counters.voxelized_triangles describe it.
  CcdVoxelBackend* voxel_backend = nullptr;
  int voxel_grid = 0;   ///< its CcdVoxelOptions::grid_resolution (0: automatic)
  int voxel_slots = 0;  ///< its CcdVoxelOptions::slots (0: default)
};

/// The objects of `from` that take part in the step, with the reason for each one left out.
struct CcdParticipants {
  std::vector<Index> objects;  ///< ids in `from`, ascending
  std::vector<CcdSkipped> skipped;
};
CcdParticipants ccd_participants(const Frame& from, const Frame& to);

/// The objects of `to` in `from`'s order: object i of the result is from.objects[i]'s
/// counterpart in `to`, or an object without topology when it has none (ccd_participants()
/// skips it). Components of meshes ("objects": "components", ComponentOrigin) are matched by
/// their origin: the piece of `to` holding the same vertices of the same mesh (pieces are
/// renumbered when one in front of them breaks, and pieces with equal faces are common, so
/// names and faces cannot tell them apart). Other objects are matched by name (files that
/// list their objects in another order). Nullopt, for matching by position, when every object
/// is at its position already, when a name (or a component) occurs twice in either frame, or,
/// for names, when no object's name is found at another position of `to` (names that change
/// with every frame, such as file names).
std::optional<Frame> ccd_counterparts(const Frame& from, const Frame& to);

/// Swept geometry of a step shared by Stage I, II and III.
struct CcdSweep {
  CcdParticipants participants;
  /// Culling margin of the whole step (see above): at least the margin of any pair of its
  /// objects (pair_margin()). Stage II widens its prisms by it.
  double margin = 0;
  /// Per object: its swept box (both frames, all vertices; not widened) and the largest
  /// coordinate magnitude in it.
  std::vector<AABB> raw_objects;
  std::vector<double> magnitudes;
  /// The culling margin of a pair of objects: ccd_margin_between() of their swept boxes (it
  /// bounds the margins of all their triangle pairs). One far-away object does not widen the
  /// margins of the others.
  double pair_margin(Index i, Index j) const;
  /// [object][triangle] each triangle's share of the culling margin (ccd_tolerance_share() of
  /// its swept box plus rounding slack, so that two triangles' shares add up to at least their
  /// ccd_margin_between() wherever their boxes come that close), and its swept box widened by
  /// it; empty for skipped objects.
  std::vector<std::vector<double>> shares;
  std::vector<std::vector<AABB>> triangles;
  std::vector<AABB> objects;  ///< union of an object's swept triangle boxes
  /// [object][vertex] the segment from the vertex's start to its end position, boxed (not
  /// widened), empty for skipped objects.
  std::vector<std::vector<AABB>> vertices;
  static CcdSweep compute(const Frame& from, const Frame& to, int threads);
};

/// The culling margin of two point sets with boxes a and b: ccd_max_tolerance() for the box
/// of both (its largest side and coordinate magnitude; the kernel's δ of any query whose
/// points lie in a or b is at most that) plus rounding_slack() of that magnitude.
double ccd_margin_between(const AABB& a, const AABB& b);

/// The whole pipeline: Stage I, Stage II when opts.voxels is set, Stage III.
/// Deterministic: the result does not depend on the thread count.
CcdStepResult continuous_collisions(const Frame& from, const Frame& to, const CcdSweep& sweep,
                                    const CcdOptions& opts);
CcdStepResult continuous_collisions(const Frame& from, const Frame& to, const CcdOptions& opts);

/// Every vertex–face and edge–edge pair of the participating objects, no culling: the
/// reference for tests. The same exclusions, argument order and output order.
CcdStepResult continuous_collisions_brute_force(const Frame& from, const Frame& to);

}  // namespace vproxq
