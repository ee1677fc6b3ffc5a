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

/// Rows 0..rows-1, row r being what fill(r, row) appends, sorted, duplicates removed. Sorting
/// each short row on its own is much cheaper than sorting all (row, value) pairs at once.
template <typename Fill>
IndexRows make_rows_by_row(std::size_t rows, const Fill& fill) {
  IndexRows out;
  out.offsets.assign(rows + 1, 0);
  std::vector<Index> row;
  for (std::size_t r = 0; r < rows; ++r) {
    row.clear();
    fill(r, row);
    std::sort(row.begin(), row.end());
    row.erase(std::unique(row.begin(), row.end()), row.end());
    out.values.insert(out.values.end(), row.begin(), row.end());
    out.offsets[r + 1] = static_cast<Index>(out.values.size());
  }
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
  ring1_ = make_rows_by_row(nt, [&](std::size_t t, std::vector<Index>& row) {
    for (Index v : topology.faces[t])
      for (Index g : vertex_triangles(v))
        if (g != static_cast<Index>(t)) row.push_back(g);
  });

  // 2-ring: the 1-rings of the 1-ring, minus t and its 1-ring; that is, the triangles of the
  // vertices of the 1-ring other than t's own (those of t's vertices are all in the 1-ring),
  // minus t's 1-ring. Going through the vertices visits each of them once per t: the cost is
  // the 1-ring plus the outer vertices' valences, where the 1-rings of the 1-ring would cost
  // the square of a high valence per triangle (a fan of 5,000 triangles around one vertex
  // took 93 s). mark[h] == t + 1: h is t, in its 1-ring, or already in its row;
  // vmark[w] == t + 1: vertex w is t's or already expanded.
  std::vector<std::size_t> mark(nt, 0);
  std::vector<std::size_t> vmark(nv, 0);
  ring2_ = make_rows_by_row(nt, [&](std::size_t t, std::vector<Index>& row) {
    const IndexSpan own = ring1(static_cast<Index>(t));
    mark[t] = t + 1;
    for (Index g : own) mark[static_cast<std::size_t>(g)] = t + 1;
    for (Index v : topology.faces[t]) vmark[static_cast<std::size_t>(v)] = t + 1;
    for (Index g : own)
      for (Index w : topology.faces[static_cast<std::size_t>(g)]) {
        std::size_t& vm = vmark[static_cast<std::size_t>(w)];
        if (vm == t + 1) continue;
        vm = t + 1;
        for (Index h : vertex_triangles(w)) {
          std::size_t& m = mark[static_cast<std::size_t>(h)];
          if (m == t + 1) continue;
          m = t + 1;
          row.push_back(h);
        }
      }
  });
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
