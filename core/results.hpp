#pragma once
// Per-frame results of the queries, as handed to the writers.
#include "core/geometry/triangle_distance.hpp"
#include "core/types.hpp"

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

/// Work counters of one query run on one frame.
struct DistanceCounters {
  std::uint64_t object_pns_pairs = 0;  ///< ordered object pairs (i, j) kept by the broad phase
  std::uint64_t feature_pns = 0;   ///< feature-level PNS: (triangle, object) pairs kept by culling
  std::uint64_t exact_tests = 0;       ///< triangle–triangle distance evaluations
};

/// Wall-clock milliseconds per stage.
struct StageTimes {
  double load = 0, aabb = 0, voronoi = 0, exact = 0, write = 0, total = 0;
};

/// What Stage II did on one frame (absent when it did not run).
struct VoronoiFrameStats {
  std::array<std::int32_t, 3> grid_dims{0, 0, 0};  ///< voxels per axis
  double cell = 0;             ///< voxel side
  double delta = 0;            ///< Lemma 2's δ = cell diagonal / 2 + slack + δ_precision
  double delta_precision = 0;  ///< the backend's arithmetic error bound
  std::uint64_t sample_voxels = 0;
  double setup_ms = 0, upload_ms = 0, compute_ms = 0, readback_ms = 0, scan_ms = 0;
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
  std::uint64_t triangle_pairs = 0;   ///< candidate triangle pairs after culling
  std::uint64_t vf_tests = 0;         ///< elementary vertex–face tests run
  std::uint64_t ee_tests = 0;         ///< elementary edge–edge tests run
  std::uint64_t limit_hits = 0;       ///< tests reported at the kernel's box limit
  std::uint64_t culled_triangles = 0;  ///< triangles dropped by Stage II (inter-object)
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
  DistanceCounters counters;
  StageTimes time_ms;
  std::optional<VoronoiFrameStats> voronoi;
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
  std::size_t frame_count = 0;  ///< frames that will be written
};

inline constexpr int kFormatVersion = 1;

}  // namespace vproxq
