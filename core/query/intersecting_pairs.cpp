#include "core/query/intersecting_pairs.hpp"

#include "core/broad_phase/object_broad_phase.hpp"
#include "core/broad_phase/triangle_bvh.hpp"
#include "core/geometry/triangle_box.hpp"
#include "core/geometry/triangle_distance.hpp"
#include "core/mesh/adjacency.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "core/voronoi/stage2.hpp"

#include <algorithm>
#include <numeric>

namespace vproxq {
namespace {

/// A unit of work: triangles [first, last) of object i against object j (i != j: either of
/// i < j and i > j, see the pairs below); or, for j == i, the pairs within object i under the
/// node pair `nodes` of its hierarchy.
struct WorkItem {
  Index i, j, first, last;
  TriangleBvh::NodePair nodes;
};

constexpr Index kChunk = 256;  // triangles per work item: enough items to balance threads

}  // namespace

IntersectingPairsOutput intersecting_pairs(const Frame& frame, const IntersectingPairsOptions& opts) {
  const FrameBoxes boxes = FrameBoxes::compute(frame, std::max(1, opts.threads));
  return intersecting_pairs(frame, boxes, opts);
}

IntersectingPairsOutput intersecting_pairs(const Frame& frame, const FrameBoxes& boxes,
                                           const IntersectingPairsOptions& opts) {
  Stopwatch sw;
  IntersectingPairsOutput out;
  const int threads = std::max(1, opts.threads);
  const size_t n = frame.objects.size();

  std::vector<WorkItem> items;
  auto add_chunks = [&](Index i, Index j) {
    const Index nt = frame.objects[static_cast<size_t>(i)].num_triangles();
    for (Index f = 0; f < nt; f += kChunk) items.push_back({i, j, f, std::min(nt, f + kChunk), {}});
  };
  const auto object_pairs = overlapping_box_pairs(boxes.object_tree(), boxes.objects, threads);
  std::vector<char> needs_bvh(n, 0);
  const std::vector<double>* apart = opts.object_distance;
  for (const auto& [i, j] : object_pairs) {
    // The inter-object distance found one of them at positive distance from every other
    // object (its answers equal brute force, whose 0 is this file's exact intersection test).
    if (apart && ((*apart)[static_cast<size_t>(i)] > 0 || (*apart)[static_cast<size_t>(j)] > 0)) continue;
    // Boxes that overlap because one object lies inside the other's closed surface (nested
    // shells): the enclosure bound keeps them apart.
    if (enclosure_lower_bound(frame, boxes, i, j) > 0) continue;
    // The object with fewer triangles searches the other's BVH: then its triangles' planes
    // prune the larger one's nodes (TrianglePlane), which is what a sliver across a fine mesh needs.
    const bool swap = frame.objects[static_cast<size_t>(j)].num_triangles() < frame.objects[static_cast<size_t>(i)].num_triangles();
    const Index from = swap ? j : i, into = swap ? i : j;
    add_chunks(from, into);
    needs_bvh[static_cast<size_t>(into)] = 1;
  }
  // Objects whose pairs within are searched here: not those whose pairs come from
  // opts.intra_pairs.
  std::vector<char> search_within(n, 0);
  if (opts.intra)
    for (size_t i = 0; i < n; ++i) {
      search_within[i] = frame.objects[i].num_triangles() > 1 && (opts.intra_pairs == nullptr || marked(opts.intra_skip, i));
      if (search_within[i]) needs_bvh[i] = 1;
    }
  boxes.build_bvhs(threads, [&](size_t i) { return needs_bvh[i] != 0; });
  // Within an object, the hierarchy descends itself (TriangleBvh::descend_self_until()):
  // neighbouring triangles share the upper levels, where a search per triangle from the root
  // went through them once for each (docs/algorithms.md, "Intersecting pairs": 1.3-2.3x less time). A pair
  // of subtrees all of whose triangles share one vertex holds no candidate (thousands of
  // triangles around one vertex overlap each other's boxes there).
  std::vector<std::vector<std::array<Index, 3>>> common(n);
  std::vector<std::vector<TriangleBvh::NodePair>> units(n);
  // Whether the descent within object i enters the node pair (a, b): overlapping boxes, and
  // not every pair of their triangles adjacent.
  auto enter = [&](size_t i, std::int32_t a, std::int32_t b) {
    const auto& ca = common[i][static_cast<size_t>(a)];
    if (a == b) return ca[0] == kNoIndex;
    const TriangleBvh& bvh = boxes.bvh(i);
    return boxes_overlap(bvh.node_box(a), bvh.node_box(b)) &&
           !TriangleBvh::adjacent_subtree(ca, common[i][static_cast<size_t>(b)]);
  };
  parallel_for(n, threads, [&](size_t i) {
    if (!search_within[i]) return;
    common[i] = boxes.bvh(i).node_common_vertices(frame.objects[i].topology->faces);
    units[i] = boxes.bvh(i).self_pairs_below(2 * kChunk, [&](std::int32_t a, std::int32_t b) { return enter(i, a, b); });
  });
  for (size_t i = 0; i < n; ++i)
    for (const auto& pair : units[i]) items.push_back({static_cast<Index>(i), static_cast<Index>(i), 0, 0, pair});

  const VoronoiBounds* voronoi = opts.voronoi;
  std::vector<std::vector<IntersectingPair>> found(items.size());
  std::vector<std::uint64_t> tests(items.size(), 0);
  parallel_for(items.size(), threads, [&](size_t k) {
    const WorkItem& w = items[k];
    const Object& oi = frame.objects[static_cast<size_t>(w.i)];
    const Object& oj = frame.objects[static_cast<size_t>(w.j)];
    const auto& tb_i = boxes.triangles[static_cast<size_t>(w.i)];
    auto& hits = found[k];
    if (w.i == w.j) {
      const size_t i = static_cast<size_t>(w.i);
      const auto& faces = oi.topology->faces;
      const auto& node_common = common[i];
      const TriangleBvh& bvh = boxes.bvh(i);
      auto test = [&](Index f, Index g) {
        ++tests[k];
        if (triangles_intersect(oi.triangle(f), oi.triangle(g)))
          hits.push_back(f < g ? IntersectingPair{w.i, f, w.i, g} : IntersectingPair{w.i, g, w.i, f});
      };
      // The descent stops at the first pair with a leaf in it. Each triangle f of the leaf then
      // searches the other side's subtree, skipping nodes strictly on one side of f's plane
      // (TrianglePlane) or all adjacent to f: a sliver across a fine mesh (whose box covers
      // much of it, and so do its ancestors', which the descent splits first, as the larger)
      // tests only the triangles near its plane. Each unordered pair of triangles lies under
      // exactly one pair the descent takes.
      bvh.descend_self_until(w.nodes, [&](std::int32_t a, std::int32_t b) { return enter(i, a, b); },
                             [&](std::int32_t a, std::int32_t b) {
        if (a == b) {
          if (!bvh.is_leaf(a)) return false;
          bvh.for_each_leaf_triangle(a, [&](Index f) {
            bvh.for_each_leaf_triangle(a, [&](Index g) {
              if (g <= f || !boxes_overlap(tb_i[static_cast<size_t>(f)], tb_i[static_cast<size_t>(g)]) ||
                  Adjacency::share_vertex(faces[static_cast<size_t>(f)], faces[static_cast<size_t>(g)]))
                return;
              test(f, g);
            });
          });
          return true;
        }
        if (!bvh.is_leaf(a) && !bvh.is_leaf(b)) return false;
        const std::int32_t leaf = bvh.is_leaf(a) ? a : b, other = leaf == a ? b : a;
        bvh.for_each_leaf_triangle(leaf, [&](Index f) {
          const Face& ff = faces[static_cast<size_t>(f)];
          const TrianglePlane plane(oi.triangle(f));
          auto skip = [&](std::int32_t node) {
            return TriangleBvh::adjacent_subtree(node_common[static_cast<size_t>(node)], ff) ||
                   plane.rejects(bvh.node_box(node));
          };
          bvh.query_overlaps(tb_i[static_cast<size_t>(f)], skip, [&](Index g) {
            if (!Adjacency::share_vertex(ff, faces[static_cast<size_t>(g)])) test(f, g);
          }, other);
        });
        return true;
      });
    } else {
      // D_l(f) > 0: f is at positive distance from every other object (Lemma 2), so it
      // touches none; only exact zeros intersect, so the comparison is with 0, no slack.
      const double* low_i = voronoi ? voronoi->triangle_lower[static_cast<size_t>(w.i)].data() : nullptr;
      const double* low_j = voronoi ? voronoi->triangle_lower[static_cast<size_t>(w.j)].data() : nullptr;
      const AABB& box_j = boxes.objects[static_cast<size_t>(w.j)];
      for (Index f = w.first; f < w.last; ++f) {
        if (low_i && low_i[f] > 0.0) continue;
        const AABB& bf = tb_i[static_cast<size_t>(f)];
        if (!boxes_overlap(bf, box_j)) continue;
        const TriangleBvh& bvh = boxes.bvh(static_cast<size_t>(w.j));
        const TrianglePlane plane(oi.triangle(f));
        bvh.query_overlaps(bf, [&](std::int32_t node) { return plane.rejects(bvh.node_box(node)); }, [&](Index g) {
          if (low_j && low_j[g] > 0.0) return;
          ++tests[k];
          if (triangles_intersect(oi.triangle(f), oj.triangle(g)))
            hits.push_back(w.i < w.j ? IntersectingPair{w.i, f, w.j, g} : IntersectingPair{w.j, g, w.i, f});
        });
      }
    }
    std::sort(hits.begin(), hits.end());
  });
  for (size_t k = 0; k < items.size(); ++k) {
    out.pairs.insert(out.pairs.end(), found[k].begin(), found[k].end());
    out.exact_tests += tests[k];
  }
  if (opts.intra && opts.intra_pairs != nullptr)
    out.pairs.insert(out.pairs.end(), opts.intra_pairs->begin(), opts.intra_pairs->end());
  // Items are already in canonical order except that intra items follow the inter ones.
  std::sort(out.pairs.begin(), out.pairs.end());
  out.ms = sw.elapsed_ms();
  return out;
}

IntersectingPairsOutput intersecting_pairs_brute_force(const Frame& frame, bool intra) {
  IntersectingPairsOutput out;
  const auto n = static_cast<Index>(frame.objects.size());
  for (Index i = 0; i < n; ++i) {
    const Object& oi = frame.objects[static_cast<size_t>(i)];
    for (Index j = intra ? i : i + 1; j < n; ++j) {
      const Object& oj = frame.objects[static_cast<size_t>(j)];
      for (Index f = 0; f < oi.num_triangles(); ++f)
        for (Index g = (i == j ? f + 1 : 0); g < oj.num_triangles(); ++g) {
          if (i == j && Adjacency::share_vertex(oi.topology->faces[static_cast<size_t>(f)],
                                                oj.topology->faces[static_cast<size_t>(g)]))
            continue;
          ++out.exact_tests;
          if (triangles_intersect(oi.triangle(f), oj.triangle(g))) out.pairs.push_back({i, f, j, g});
        }
    }
  }
  std::sort(out.pairs.begin(), out.pairs.end());
  return out;
}

}  // namespace vproxq
