#include "core/mesh/adjacency.hpp"

#include <algorithm>
#include <utility>

namespace vproxq {
namespace {

/// Rows from (row, value) pairs: sorted, duplicates removed.
IndexRows make_rows(std::size_t rows, std::vector<std::pair<Index, Index>> pairs) {
  std::sort(pairs.begin(), pairs.end());
  pairs.erase(std::unique(pairs.begin(), pairs.end()), pairs.end());
  IndexRows out;
  out.offsets.assign(rows + 1, 0);
  out.values.reserve(pairs.size());
  for (const auto& [r, v] : pairs) {
    ++out.offsets[static_cast<std::size_t>(r) + 1];
    out.values.push_back(v);
  }
  for (std::size_t r = 0; r < rows; ++r) out.offsets[r + 1] += out.offsets[r];
  return out;
}

}  // namespace

Adjacency::Adjacency(const Topology& topology) {
  const auto nv = static_cast<std::size_t>(topology.num_vertices);
  const auto nt = static_cast<std::size_t>(topology.num_triangles());

  std::vector<std::pair<Index, Index>> pairs;
  pairs.reserve(3 * nt);
  for (std::size_t t = 0; t < nt; ++t)
    for (Index v : topology.faces[t]) pairs.emplace_back(v, static_cast<Index>(t));
  vertex_tris_ = make_rows(nv, std::move(pairs));

  // Edges keyed (b, a) with a < b, so that sorting the keys gives the documented order.
  std::vector<std::pair<Index, Index>> keys;
  keys.reserve(3 * nt);
  for (const Face& f : topology.faces)
    for (int k = 0; k < 3; ++k) {
      const Index a = f[static_cast<std::size_t>(k)], b = f[static_cast<std::size_t>((k + 1) % 3)];
      if (a != b) keys.emplace_back(std::max(a, b), std::min(a, b));
    }
  std::sort(keys.begin(), keys.end());
  keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
  edges_.reserve(keys.size());
  for (const auto& [b, a] : keys) edges_.push_back({a, b});

  tri_edges_.assign(nt, {kNoIndex, kNoIndex, kNoIndex});
  std::vector<std::pair<Index, Index>> edge_pairs;
  edge_pairs.reserve(3 * nt);
  for (std::size_t t = 0; t < nt; ++t)
    for (std::size_t k = 0; k < 3; ++k) {
      const Index e = find_edge(topology.faces[t][k], topology.faces[t][(k + 1) % 3]);
      tri_edges_[t][k] = e;
      if (e != kNoIndex) edge_pairs.emplace_back(e, static_cast<Index>(t));
    }
  edge_tris_ = make_rows(edges_.size(), std::move(edge_pairs));

  // 1-ring: the triangles of the three vertices, minus t itself.
  std::vector<std::pair<Index, Index>> r1;
  for (std::size_t t = 0; t < nt; ++t)
    for (Index v : topology.faces[t])
      for (Index g : vertex_triangles(v))
        if (g != static_cast<Index>(t)) r1.emplace_back(static_cast<Index>(t), g);
  ring1_ = make_rows(nt, std::move(r1));

  // 2-ring: the 1-rings of the 1-ring, minus t and its 1-ring.
  std::vector<std::pair<Index, Index>> r2;
  std::vector<Index> row;
  for (std::size_t t = 0; t < nt; ++t) {
    row.clear();
    const IndexSpan own = ring1(static_cast<Index>(t));
    for (Index g : own)
      for (Index h : ring1(g))
        if (h != static_cast<Index>(t) && !std::binary_search(own.begin(), own.end(), h))
          row.push_back(h);
    for (Index h : row) r2.emplace_back(static_cast<Index>(t), h);
  }
  ring2_ = make_rows(nt, std::move(r2));
}

Index Adjacency::find_edge(Index a, Index b) const {
  if (a == b) return kNoIndex;
  const std::array<Index, 2> key{std::min(a, b), std::max(a, b)};
  const auto it = std::lower_bound(edges_.begin(), edges_.end(), key,
                                   [](const std::array<Index, 2>& e, const std::array<Index, 2>& k) {
                                     return e[1] < k[1] || (e[1] == k[1] && e[0] < k[0]);
                                   });
  return it != edges_.end() && *it == key ? static_cast<Index>(it - edges_.begin()) : kNoIndex;
}

const Adjacency& adjacency(const Topology& topology) {
  const AdjacencyCache& cache = topology.adjacency_cache;
  std::lock_guard<std::mutex> lock(cache.mutex_);
  if (!cache.value_) cache.value_ = std::make_shared<const Adjacency>(topology);
  return *cache.value_;
}

}  // namespace vproxq
