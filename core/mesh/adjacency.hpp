#pragma once
// Connectivity derived from a Topology (paper 5.2.2): vertex–triangle incidence, the unique
// edges, the 1-ring of each triangle (the triangles sharing at least one vertex with it: its
// adjacent features) and the 2-ring. The incidence and the edges are computed once per
// Topology and cached with it (frames that reuse a Topology, same faces, reuse them); the
// rings are derived from the incidence when asked for, one triangle at a time, and not stored:
// a vertex used by V triangles puts all of them in each other's 1-ring, so stored rings cost
// memory of the order of V^2 (a cylinder whose caps are fans of 10,000 triangles needed 6 GB).
// What the 2-ring bound needs per frame, the 2-ring's vertices, is cached (ring2_vertices()),
// walked around such hubs.
//
// Behaviour on irregular meshes (documented in docs/algorithms.md, "Intra-object distance"):
//  - boundary and non-manifold edges: an edge simply lists every triangle that uses it (1, 2
//    or more); rings are defined by shared vertices, so nothing needs a manifold;
//  - duplicate triangles (same three vertices) share all their vertices, so each is in the
//    other's 1-ring;
//  - isolated vertices (used by no face) have no incident triangles and no edges;
//  - degenerate faces with a repeated vertex ({a, a, b}) are kept; their repeated "edge" (a, a)
//    is not an edge.
#include "core/mesh/topology.hpp"

#include <cstddef>
#include <mutex>
#include <vector>

namespace vproxq {

/// A read-only view of a contiguous run of indices.
struct IndexSpan {
  const Index* first = nullptr;
  const Index* last = nullptr;
  const Index* begin() const { return first; }
  const Index* end() const { return last; }
  std::size_t size() const { return static_cast<std::size_t>(last - first); }
  bool empty() const { return first == last; }
  Index operator[](std::size_t k) const { return first[k]; }
};

/// Compressed rows: row r is values[offsets[r] .. offsets[r+1]).
struct IndexRows {
  std::vector<Index> offsets{0};
  std::vector<Index> values;

  std::size_t rows() const { return offsets.size() - 1; }
  IndexSpan row(Index r) const {
    const auto k = static_cast<std::size_t>(r);
    return {values.data() + offsets[k], values.data() + offsets[k + 1]};
  }
};

class Adjacency {
 public:
  explicit Adjacency(const Topology& topology);

  /// Triangles using vertex v, ascending.
  IndexSpan vertex_triangles(Index v) const { return vertex_tris_.row(v); }
  /// Unique undirected edges {a, b} with a < b, sorted by (b, a): the order the cloth-funnel
  /// CCD data uses for its edge ids.
  const std::vector<std::array<Index, 2>>& edges() const { return edges_; }
  /// Edge ids of triangle t: edge k joins corners k and (k+1) % 3 (kNoIndex for a repeated
  /// vertex).
  const std::array<Index, 3>& triangle_edges(Index t) const {
    return tri_edges_[static_cast<std::size_t>(t)];
  }
  /// Triangles using edge e, ascending.
  IndexSpan edge_triangles(Index e) const { return edge_tris_.row(e); }
  /// Edge id of {a, b} (either order), or kNoIndex when no face has that edge.
  Index find_edge(Index a, Index b) const;
  /// The 1-ring of t: every other triangle sharing at least one vertex with t, ascending.
  /// Computed on each call, in time of the order of the valences of t's vertices.
  std::vector<Index> ring1(Index t) const;
  /// The 2-ring of t: triangles sharing a vertex with a triangle of the 1-ring, that are
  /// neither t nor in its 1-ring, ascending. Computed on each call (the 1-ring's vertices'
  /// valences).
  std::vector<Index> ring2(Index t) const;

  /// Vertices used by more than this many triangles are hubs, which ring2_vertices() does not
  /// walk through.
  static constexpr std::size_t kRingWalkValence = 64;
  /// The vertices of t's 2-ring triangles that a walk from t's vertices through the 1-ring
  /// reaches without passing through a hub (as a vertex of t or of the 1-ring): ascending,
  /// none of them t's. Without hubs nearby, exactly the 2-ring's vertices; around a hub of
  /// valence V, the whole 2-ring would cost of the order of V per triangle, V^2 in all.
  /// Computed for every triangle on the first call (thread-safe) and cached.
  IndexSpan ring2_vertices(Index t) const;
  /// Computes what ring2_vertices() returns for every triangle, on up to `threads` threads,
  /// unless done already (later calls return at once).
  void prepare_ring2_vertices(int threads) const;

  /// True when faces f and g share a vertex (f == g included): "adjacent" in DESIGN.md.
  static bool share_vertex(const Face& f, const Face& g) {
    for (Index a : f)
      for (Index b : g)
        if (a == b) return true;
    return false;
  }

 private:
  IndexRows vertex_tris_;
  std::vector<std::array<Index, 2>> edges_;
  /// The edges {a, b} with b the larger vertex: edges_[first_edge_[b], first_edge_[b + 1]).
  std::vector<Index> first_edge_;
  std::vector<std::array<Index, 3>> tri_edges_;
  IndexRows edge_tris_;
  std::vector<Face> faces_;
  mutable std::once_flag ring2_vertices_once_;
  mutable IndexRows ring2_vertices_;
};

/// The adjacency of a topology, computed on first use and cached inside it (thread-safe).
const Adjacency& adjacency(const Topology& topology);

}  // namespace vproxq
