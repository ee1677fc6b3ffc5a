#pragma once
// Connectivity derived from a Topology (paper 5.2.2): vertex–triangle incidence, the unique
// edges, the 1-ring of each triangle (the triangles sharing at least one vertex with it: its
// adjacent features) and the 2-ring. Computed once per Topology and cached with it; frames
// that reuse a Topology (same faces) reuse its adjacency.
//
// Behaviour on irregular meshes (documented in the README):
//  - boundary and non-manifold edges: an edge simply lists every triangle that uses it (1, 2
//    or more); rings are defined by shared vertices, so nothing needs a manifold;
//  - duplicate triangles (same three vertices) share all their vertices, so each is in the
//    other's 1-ring;
//  - isolated vertices (used by no face) have no incident triangles and no edges;
//  - degenerate faces with a repeated vertex ({a, a, b}) are kept; their repeated "edge" (a, a)
//    is not an edge.
#include "core/mesh/topology.hpp"

#include <cstddef>
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
  IndexSpan ring1(Index t) const { return ring1_.row(t); }
  /// The 2-ring of t: triangles sharing a vertex with a triangle of the 1-ring, that are
  /// neither t nor in its 1-ring, ascending.
  IndexSpan ring2(Index t) const { return ring2_.row(t); }

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
  std::vector<std::array<Index, 3>> tri_edges_;
  IndexRows edge_tris_;
  IndexRows ring1_;
  IndexRows ring2_;
};

/// The adjacency of a topology, computed on first use and cached inside it (thread-safe).
const Adjacency& adjacency(const Topology& topology);

}  // namespace vproxq
