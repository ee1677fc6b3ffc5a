#pragma once
// Per-frame results of the queries, as handed to the writers.
#include "core/geometry/triangle_distance.hpp"
#include "core/types.hpp"

#include <array>
#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace vproxq {

/// For one object: its nearest other object in the frame and how they come closest.
/// With no other object in the frame, nearest_object is kNoIndex and distance is infinite.
struct InterObjectDistance {
  Index object = kNoIndex;
  Index nearest_object = kNoIndex;
  double distance = kInfinity;  ///< 0 when touching or intersecting
  std::array<Index, 2> triangles{kNoIndex, kNoIndex};  ///< {on object, on nearest_object}
  std::array<Vec3, 2> points{Vec3::Zero(), Vec3::Zero()};
  TriangleDistanceCase kind = TriangleDistanceCase::Intersecting;

  bool has_nearest() const { return nearest_object != kNoIndex; }
};

/// Intra-object ("self") distance of one triangle f: its nearest non-adjacent triangle of the
/// same object (adjacent = shares a vertex; f itself excluded). nearest is kNoIndex (distance
/// infinite) when every other triangle of the object shares a vertex with f.
struct IntraTriangleNearest {
  Index nearest = kNoIndex;
  double distance = kInfinity;  ///< 0 when f and nearest touch or intersect
  std::array<Vec3, 2> points{Vec3::Zero(), Vec3::Zero()};  ///< {on f, on nearest}
  TriangleDistanceCase kind = TriangleDistanceCase::Intersecting;  ///< from f's side
};

/// Intra-object distance of one object: per triangle its nearest non-adjacent triangle, and the
/// object's minimum, the smallest (distance, triangle, nearest) over its triangles. Without any
/// non-adjacent pair, triangles are kNoIndex and distance is infinite.
struct IntraObjectDistance {
  Index object = kNoIndex;
  double distance = kInfinity;
  std::array<Index, 2> triangles{kNoIndex, kNoIndex};  ///< {f, its nearest}
  std::array<Vec3, 2> points{Vec3::Zero(), Vec3::Zero()};
  std::vector<IntraTriangleNearest> per_triangle;  ///< indexed by triangle

  bool has_pair() const { return triangles[0] != kNoIndex; }
};

/// Work counters of one query run on one frame.
struct DistanceCounters {
  std::uint64_t object_pns_pairs = 0;  ///< ordered object pairs (i, j) kept by the broad phase
  std::uint64_t feature_pns = 0;   ///< feature-level PNS: (triangle, object) pairs kept by culling
  std::uint64_t exact_tests = 0;       ///< triangle–triangle distance evaluations
  /// Triangle pairs whose boxes were within the bound but that the separating-axis lower
  /// bound (core/geometry/separation_bound.hpp) skipped: no exact test ran for them.
  std::uint64_t separation_culled = 0;
  /// Intra-object query: non-adjacent (f, g) pairs whose boxes passed the AABB test, how many of
  /// those Stage II's bounds culled, how many the separating-axis bound culled, how many were
  /// not evaluated again because g's search had already evaluated (g, f), and the
  /// triangle–triangle distance evaluations that ran. With more than one thread, the counts
  /// after Stage II's depend on the threads' timing (the results do not).
  std::uint64_t intra_candidates = 0;
  std::uint64_t intra_voronoi_culled = 0;
  std::uint64_t intra_separation_culled = 0;
  std::uint64_t intra_reused = 0;
  std::uint64_t intra_exact_tests = 0;
};

/// Wall-clock milliseconds per stage.
struct StageTimes {
  double load = 0, aabb = 0, voronoi = 0, exact = 0, write = 0, total = 0;
  /// The intra-object query's shares: of aabb (its 2-ring bounds, paper 5.2.2), of voronoi
  /// (self Stage II) and of exact (its Stage III).
  double intra_bounds = 0, intra_voronoi = 0, intra_exact = 0;
};

/// What Stage II did on one frame (absent when it did not run).
struct VoronoiFrameStats {
  std::array<std::int32_t, 3> grid_dims{0, 0, 0};  ///< voxels per axis
  double cell = 0;             ///< voxel side
  double delta = 0;            ///< Lemma 2's δ = cell diagonal / 2 + slack + δ_precision
  double delta_precision = 0;  ///< the backend's arithmetic error bound
  std::uint64_t sample_voxels = 0;
  std::uint64_t samples = 0;  ///< samples evaluated: (voxel, triangle) pairs for the self Stage II, = sample_voxels for the inter-object one
  /// Self Stage II only: triangles sampled (2-ring bound above δ); none for the inter-object one.
  std::optional<std::uint64_t> sampled_triangles;
  std::uint64_t backend_triangles = 0;  ///< triangles passed to the backend (those a sample can reach)
  double setup_ms = 0, upload_ms = 0, compute_ms = 0, readback_ms = 0, scan_ms = 0;
};

/// One intersecting triangle pair (closed triangles sharing a point, decided exactly).
/// Canonical: object_a <= object_b, and tri_a < tri_b when the objects are the same (an
/// intra-object pair: two triangles of one object that share no vertex).
struct IntersectingPair {
  Index object_a = kNoIndex, tri_a = kNoIndex, object_b = kNoIndex, tri_b = kNoIndex;

  bool operator==(const IntersectingPair& o) const {
    return object_a == o.object_a && tri_a == o.tri_a && object_b == o.object_b && tri_b == o.tri_b;
  }
  bool operator!=(const IntersectingPair& o) const { return !(*this == o); }
  /// Lexicographic (object_a, object_b, tri_a, tri_b): the order of the written list.
  bool operator<(const IntersectingPair& o) const {
    if (object_a != o.object_a) return object_a < o.object_a;
    if (object_b != o.object_b) return object_b < o.object_b;
    if (tri_a != o.tri_a) return tri_a < o.tri_a;
    return tri_b < o.tri_b;
  }
};

/// Outcome of the local penetration depth of one object pair (docs/algorithms.md, "Local penetration depth").
enum class PdStatus : std::uint8_t {
  Ok = 0,             ///< depth and direction computed
  OpenSurface = 1,    ///< an object has a boundary edge (used by one face): no inside
  NonManifold = 2,    ///< an object has an edge used by three or more faces
  NonOrientable = 3,  ///< an edge is used twice in the same direction: no consistent inside
  TooDeep = 4,        ///< the overlap holds a whole connected part of an object: no local answer
  Shallow = 5,        ///< no vertex lies strictly inside the other object and no overlapping
                      ///< triangle has a normal (all degenerate): no direction to measure along
  SelfIntersection = 6,  ///< a self-intersection whose sheets the method cannot tell apart
                         ///< (docs/algorithms.md): no number
};

/// Stable text of a PdStatus (JSON "status", README).
inline const char* pd_status_name(PdStatus s) {
  switch (s) {
    case PdStatus::Ok: return "ok";
    case PdStatus::OpenSurface: return "open_surface";
    case PdStatus::NonManifold: return "non_manifold";
    case PdStatus::NonOrientable: return "non_orientable";
    case PdStatus::TooDeep: return "too_deep";
    case PdStatus::Shallow: return "shallow";
    case PdStatus::SelfIntersection: return "self_intersection";
  }
  return "unknown";
}

/// Why a self-intersection entry has no number (status SelfIntersection; docs/algorithms.md, "Where it
/// gives no number"): the first of the undecided tests that stopped its contact.
enum class PdReason : std::uint8_t {
  None = 0,
  DegenerateStar = 1,      ///< a vertex whose star has no face with a normal (reason_features: v)
  FlatFold = 2,            ///< a face of a vertex's star is covered coplanarly by another (v)
  ReferenceVertex = 3,     ///< the component's reference vertex (given) is undecided itself
  SheetsNotSeparated = 4,  ///< R(C) holds both triangles of an intersecting pair (given)
  WholeObject = 5,         ///< the own sheet R(C) is the whole object: nothing across the
                           ///< curve for the vertex given
};

/// Stable text of a PdReason (JSON "reason", README).
inline const char* pd_reason_name(PdReason r) {
  switch (r) {
    case PdReason::None: return "none";
    case PdReason::DegenerateStar: return "degenerate_star";
    case PdReason::FlatFold: return "flat_fold";
    case PdReason::ReferenceVertex: return "reference_vertex";
    case PdReason::SheetsNotSeparated: return "sheets_not_separated";
    case PdReason::WholeObject: return "whole_object";
  }
  return "unknown";
}

/// Local penetration depth of one intersecting object pair (paper 3.3).
struct PenetrationDepth {
  std::array<Index, 2> objects{kNoIndex, kNoIndex};  ///< objects[0] <= objects[1]
  PdStatus status = PdStatus::Ok;
  double depth = 0;  ///< meaningful only when status is Ok
  /// Unit translation of objects[0] that undoes the penetration (objects[1] moves by its
  /// negative); meaningful only when status is Ok.
  Vec3 direction = Vec3::Zero();
  /// The closest-feature pair of maximal distance that gave the direction: a vertex of
  /// deepest_object inside the other object, and its nearest point on the other's surface
  /// (kNoIndex when the direction came from a face normal: no vertex strictly inside).
  Index deepest_object = kNoIndex;
  Index deepest_vertex = kNoIndex;
  Vec3 deepest_point = Vec3::Zero();    ///< the vertex
  Vec3 nearest_point = Vec3::Zero();    ///< its nearest point on the other object
  /// Overlapping features, ascending ids: vertices of objects[k] inside objects[1-k], and the
  /// triangles of objects[k] that intersect objects[1-k] or touch such a vertex.
  std::array<std::vector<Index>, 2> inside_vertices;
  std::array<std::vector<Index>, 2> overlapping_triangles;
  /// Status SelfIntersection only: which test left the entry undecided, and where: a vertex
  /// (reason_features[1] kNoIndex) or, for SheetsNotSeparated, the pair's two triangles.
  PdReason reason = PdReason::None;
  std::array<Index, 2> reason_features{kNoIndex, kNoIndex};
};

/// CCD (paper 3.2, 5.3): a vertex–face pair that collides between frame k and k+1. Ids index
/// each object's own vertex and face arrays (file order).
struct CcdVertexFace {
  Index object_v = kNoIndex;
  Index vertex = kNoIndex;
  Index object_f = kNoIndex;
  Index face = kNoIndex;
  double toi = 1;  ///< earliest time of impact in [0, 1] (a lower bound, see geometry/ccd.hpp)
};

/// CCD: an edge–edge pair that collides; edges as vertex pairs (a < b), the edge with the
/// smaller (object, edge id) first.
struct CcdEdgeEdge {
  Index object_a = kNoIndex;
  std::array<Index, 2> edge_a{kNoIndex, kNoIndex};
  Index object_b = kNoIndex;
  std::array<Index, 2> edge_b{kNoIndex, kNoIndex};
  double toi = 1;
};

/// CCD per object pair (objects[0] <= objects[1]; equal for self-collisions).
struct CcdObjectPair {
  std::array<Index, 2> objects{kNoIndex, kNoIndex};
  double toi = 1;                    ///< earliest TOI over its colliding primitive pairs
  std::uint64_t primitive_pairs = 0;  ///< colliding vertex–face plus edge–edge pairs
};

/// An object left out of CCD for a step, and why (topology change, no counterpart).
struct CcdSkipped {
  Index object = kNoIndex;
  std::string reason;
};

struct CcdCounters {
  std::uint64_t object_pairs = 0;     ///< object pairs (i <= j) whose swept boxes overlap
  /// Candidate triangle pairs after the box culling (Stage I's BVH walk).
  std::uint64_t triangle_pairs = 0;
  /// Of those, pairs shown apart for the whole step along a separating axis (no tests ran); for
  /// two triangles of one object sharing one vertex, all their primitive pairs along one axis.
  std::uint64_t separated_pairs = 0;
  /// Of the rest, pairs Stage II rules out (no tests ran; it looks at inter-object pairs only):
  /// one of the two triangles has no (slot, voxel) key that another object marks, or the two
  /// share no key.
  std::uint64_t unshared_pairs = 0;
  /// Primitive pairs (vertex–face, edge–edge) shown apart for the whole step along a
  /// separating axis (no test ran).
  std::uint64_t separated_primitives = 0;
  std::uint64_t vf_tests = 0;         ///< elementary vertex–face tests run
  std::uint64_t ee_tests = 0;         ///< elementary edge–edge tests run
  std::uint64_t limit_hits = 0;       ///< tests reported at the kernel's box limit
  /// Inter-object: (object pair, triangle of the first) whose candidate pairs Stage II drops
  /// whole, the triangle having no key that another object marks.
  std::uint64_t culled_triangles = 0;
  /// Triangles Stage II voxelized (those of the inter-object pairs left after the
  /// separating-axis tests).
  std::uint64_t voxelized_triangles = 0;
  std::uint64_t elementary_tests() const { return vf_tests + ee_tests; }
};

/// The CCD step from this frame to `to_frame`, sorted canonically: vf by (object_v, vertex,
/// object_f, face), ee by (object_a, edge_a, object_b, edge_b), pairs by objects.
struct CcdStepResult {
  int to_frame = 0;
  std::vector<CcdSkipped> skipped;
  std::vector<CcdObjectPair> pairs;
  std::vector<CcdVertexFace> vf;
  std::vector<CcdEdgeEdge> ee;
  CcdCounters counters;
  double aabb_ms = 0, voronoi_ms = 0, exact_ms = 0;
  /// Stage II was asked for (it runs only where Stage I leaves a pair to test).
  bool stage2 = false;
  /// Stage II's space-time grid when it ran: voxels per axis and the cell's side.
  std::optional<std::array<std::int32_t, 3>> voxel_grid;
  double voxel_cell = 0;
};

struct ObjectInfo {
  Index id = 0;
  std::string name;
  Index vertices = 0;
  Index triangles = 0;
  bool is_static = false;
};

struct FrameResult {
  int frame = 0;  ///< position in the scene's sequence
  std::vector<std::string> files;
  std::vector<ObjectInfo> objects;
  std::optional<std::vector<InterObjectDistance>> inter;  ///< set when "distance" ran
  /// Every intersecting triangle pair, sorted (set when "distance" or "pd" ran).
  std::optional<std::vector<IntersectingPair>> intersecting_pairs;
  std::uint64_t intersection_tests = 0;  ///< exact triangle–triangle intersection tests
  std::optional<std::vector<PenetrationDepth>> pd;  ///< set when "pd" ran; one per object pair
  std::optional<std::vector<IntraObjectDistance>> intra;  ///< set when "distance" ran
  DistanceCounters counters;
  StageTimes time_ms;
  std::optional<VoronoiFrameStats> voronoi;
  std::optional<VoronoiFrameStats> self_voronoi;  ///< the intra-object query's Stage II
  /// Set when "ccd" ran and the scene has a next frame (absent on its last frame).
  std::optional<CcdStepResult> ccd;
};

/// What a run was asked and how it ran; written once at the top of each output file.
struct RunInfo {
  std::string tool_version = VPROXQ_VERSION;
  std::string scene;                 ///< scene path as given
  std::string scene_name;            ///< scene.json "name" (or the file stem)
  std::vector<std::string> queries;  ///< in canonical order
  std::string voronoi = "off";       ///< the backend that ran
  int grid = 0;                      ///< 0: no grid (voronoi off)
  std::string device;                ///< renderer string, or "" without GPU
  int threads = 1;
  bool self = true;             ///< whether "distance" ran its intra-object part (--self)
  std::size_t frame_count = 0;  ///< frames that will be written
};

inline constexpr int kFormatVersion = 1;

}  // namespace vproxq
