#include "core/mesh/adjacency.hpp"

#include "core/parallel.hpp"

#include <algorithm>
#include <utility>

namespace vproxq {
namespace {

/// Compressed rows filled by counting: `each(emit)` calls emit(row, value) for every entry,
/// twice over (once to count, once to place) in the same order; rows keep that order.
template <typename Each>
IndexRows counted_rows(std::size_t rows, const Each& each) {
  IndexRows out;
  out.offsets.assign(rows + 1, 0);
  each([&](Index r, Index) { ++out.offsets[static_cast<std::size_t>(r) + 1]; });
  for (std::size_t r = 0; r < rows; ++r) out.offsets[r + 1] += out.offsets[r];
  out.values.resize(static_cast<std::size_t>(out.offsets[rows]));
  std::vector<Index> next(out.offsets.begin(), out.offsets.end() - 1);
  each([&](Index r, Index v) { out.values[static_cast<std::size_t>(next[static_cast<std::size_t>(r)]++)] = v; });
  return out;
}

}  // namespace

// Rows are filled by counting, in triangle order, so each comes out ascending; a face's
// repeated vertex or edge is emitted once. (Sorting (row, value) pairs took 12 ms of the
// 38 ms that the first frame of funnel-227, 18,484 triangles, spent on its topology.)
Adjacency::Adjacency(const Topology& topology) {
  const auto nv = static_cast<std::size_t>(topology.num_vertices);
  const auto nt = static_cast<std::size_t>(topology.num_triangles());
  const auto& faces = topology.faces;

  vertex_tris_ = counted_rows(nv, [&](auto&& emit) {
    for (std::size_t t = 0; t < nt; ++t) {
      const Face& f = faces[t];
      for (std::size_t k = 0; k < 3; ++k)
        if ((k < 1 || f[k] != f[0]) && (k < 2 || f[k] != f[1])) emit(f[k], static_cast<Index>(t));
    }
  });

  // Edges {a, b}, a < b, grouped by b (counting), each group's a sorted and made unique: the
  // documented (b, a) order. A face's edge k gets its id from its group (find_edge()).
  const IndexRows by_high = counted_rows(nv, [&](auto&& emit) {
    for (const Face& f : faces)
      for (std::size_t k = 0; k < 3; ++k) {
        const Index a = f[k], b = f[(k + 1) % 3];
        if (a != b) emit(std::max(a, b), std::min(a, b));
      }
  });
  first_edge_.assign(nv + 1, 0);
  edges_.reserve(by_high.values.size() / 2 + 1);
  std::vector<Index> group;
  for (std::size_t b = 0; b < nv; ++b) {
    first_edge_[b] = static_cast<Index>(edges_.size());
    const IndexSpan row = by_high.row(static_cast<Index>(b));
    group.assign(row.begin(), row.end());
    std::sort(group.begin(), group.end());
    group.erase(std::unique(group.begin(), group.end()), group.end());
    for (const Index a : group) edges_.push_back({a, static_cast<Index>(b)});
  }
  first_edge_[nv] = static_cast<Index>(edges_.size());
  tri_edges_.assign(nt, {kNoIndex, kNoIndex, kNoIndex});
  for (std::size_t t = 0; t < nt; ++t)
    for (std::size_t k = 0; k < 3; ++k) tri_edges_[t][k] = find_edge(faces[t][k], faces[t][(k + 1) % 3]);
  edge_tris_ = counted_rows(edges_.size(), [&](auto&& emit) {
    for (std::size_t t = 0; t < nt; ++t) {
      const auto& e = tri_edges_[t];
      for (std::size_t k = 0; k < 3; ++k)
        if (e[k] != kNoIndex && (k < 1 || e[k] != e[0]) && (k < 2 || e[k] != e[1])) emit(e[k], static_cast<Index>(t));
    }
  });

  faces_ = faces;
}

std::vector<Index> Adjacency::ring1(Index t) const {
  std::vector<Index> row;
  for (Index v : faces_[static_cast<std::size_t>(t)])
    for (Index g : vertex_triangles(v))
      if (g != t) row.push_back(g);
  std::sort(row.begin(), row.end());
  row.erase(std::unique(row.begin(), row.end()), row.end());
  return row;
}

std::vector<Index> Adjacency::ring2(Index t) const {
  // The triangles of the 1-ring's vertices other than t's own (those of t's vertices are all
  // in the 1-ring), minus the 1-ring.
  const Face& f = faces_[static_cast<std::size_t>(t)];
  std::vector<Index> row;
  for (Index g : ring1(t))
    for (Index w : faces_[static_cast<std::size_t>(g)]) {
      if (w == f[0] || w == f[1] || w == f[2]) continue;
      for (Index h : vertex_triangles(w))
        if (!share_vertex(f, faces_[static_cast<std::size_t>(h)])) row.push_back(h);
    }
  std::sort(row.begin(), row.end());
  row.erase(std::unique(row.begin(), row.end()), row.end());
  return row;
}

void Adjacency::prepare_ring2_vertices(int threads) const {
  std::call_once(ring2_vertices_once_, [&] {
    const std::size_t nt = faces_.size(), nv = vertex_tris_.rows();
    auto walked = [&](Index v) { return vertex_triangles(v).size() <= kRingWalkValence; };
    // Rows per block of triangles, in parallel, then concatenated in triangle order. A few
    // blocks per thread: each block clears marks over all vertices and triangles.
    const std::size_t kRowsPerBlock =
        std::max<std::size_t>(1024, (nt + 4 * static_cast<std::size_t>(std::max(threads, 1)) - 1) /
                                        (4 * static_cast<std::size_t>(std::max(threads, 1))));
    const std::size_t blocks = (nt + kRowsPerBlock - 1) / kRowsPerBlock;
    std::vector<std::vector<Index>> values(blocks);
    std::vector<std::vector<Index>> counts(blocks);
    parallel_for(blocks, threads, [&](std::size_t blk) {
      // Marks instead of sorting: entry == stamp means seen for the current triangle.
      std::vector<std::uint32_t> outer_mark(nv, 0), vert_mark(nv, 0), tri_mark(nt, 0);
      std::uint32_t stamp = 0;
      std::vector<Index> outer, verts;
      for (std::size_t u = blk * kRowsPerBlock; u < std::min(nt, (blk + 1) * kRowsPerBlock); ++u) {
        ++stamp;
        const Face& f = faces_[u];
        auto own = [&](Index v) { return v == f[0] || v == f[1] || v == f[2]; };
        // The 1-ring's vertices other than f's own, through f's walked vertices; their
        // triangles that share no vertex with f (2-ring triangles); those triangles' vertices.
        outer.clear();
        for (Index v : f)
          if (walked(v))
            for (Index g : vertex_triangles(v))
              for (Index w : faces_[static_cast<std::size_t>(g)])
                if (!own(w) && walked(w) && outer_mark[static_cast<std::size_t>(w)] != stamp) {
                  outer_mark[static_cast<std::size_t>(w)] = stamp;
                  outer.push_back(w);
                }
        verts.clear();
        for (Index w : outer)
          for (Index h : vertex_triangles(w)) {
            std::uint32_t& m = tri_mark[static_cast<std::size_t>(h)];
            if (m == stamp) continue;
            m = stamp;
            const Face& hf = faces_[static_cast<std::size_t>(h)];
            if (share_vertex(f, hf)) continue;
            for (Index b : hf)
              if (vert_mark[static_cast<std::size_t>(b)] != stamp) {
                vert_mark[static_cast<std::size_t>(b)] = stamp;
                verts.push_back(b);
              }
          }
        std::sort(verts.begin(), verts.end());
        values[blk].insert(values[blk].end(), verts.begin(), verts.end());
        counts[blk].push_back(static_cast<Index>(verts.size()));
      }
    });
    IndexRows rows;
    rows.offsets.assign(nt + 1, 0);
    std::size_t u = 0;
    for (std::size_t blk = 0; blk < blocks; ++blk) {
      for (const Index c : counts[blk]) {
        rows.offsets[u + 1] = rows.offsets[u] + c;
        ++u;
      }
      rows.values.insert(rows.values.end(), values[blk].begin(), values[blk].end());
    }
    ring2_vertices_ = std::move(rows);
  });
}

IndexSpan Adjacency::ring2_vertices(Index t) const {
  prepare_ring2_vertices(1);
  return ring2_vertices_.row(t);
}

// A binary search in the group of the larger vertex: a hub's group holds thousands of edges
// (a fan of 20,000 triangles), all of them in the constructor's lookups.
Index Adjacency::find_edge(Index a, Index b) const {
  if (a == b) return kNoIndex;
  const Index lo = std::min(a, b), hi = std::max(a, b);
  if (lo < 0 || static_cast<std::size_t>(hi) + 1 >= first_edge_.size()) return kNoIndex;
  const auto first = edges_.begin() + first_edge_[static_cast<std::size_t>(hi)];
  const auto last = edges_.begin() + first_edge_[static_cast<std::size_t>(hi) + 1];
  const auto it = std::lower_bound(first, last, lo, [](const std::array<Index, 2>& e, Index v) { return e[0] < v; });
  return it != last && (*it)[0] == lo ? static_cast<Index>(it - edges_.begin()) : kNoIndex;
}

const Adjacency& adjacency(const Topology& topology) {
  const AdjacencyCache& cache = topology.adjacency_cache;
  std::lock_guard<std::mutex> lock(cache.mutex_);
  if (!cache.value_) cache.value_ = std::make_shared<const Adjacency>(topology);
  return *cache.value_;
}

}  // namespace vproxq
