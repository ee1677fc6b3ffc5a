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

/// A unit of work: triangles [first, last) of object i against object j (j == i: within i;
/// either of i < j and i > j for two objects, see the pairs below).
struct WorkItem {
  Index i, j, first, last;
};

constexpr Index kChunk = 256;  // triangles per work item: enough items to balance threads

/// The sum of a box's sides.
double box_size(const AABB& b) { return (b.hi - b.lo).sum(); }

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
    for (Index f = 0; f < nt; f += kChunk) items.push_back({i, j, f, std::min(nt, f + kChunk)});
  };
  const auto object_pairs = overlapping_box_pairs(boxes.object_tree(), boxes.objects, threads);
  std::vector<char> needs_bvh(n, 0);
  for (const auto& [i, j] : object_pairs) {
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
  // Objects whose pairs within come from opts.intra_pairs.
  const auto intra_known = [&](size_t i) { return opts.intra_pairs != nullptr && !marked(opts.intra_skip, i); };
  if (opts.intra) {
    for (size_t i = 0; i < n; ++i) {
      if (intra_known(i)) continue;
      add_chunks(static_cast<Index>(i), static_cast<Index>(i));
      needs_bvh[i] = 1;
    }
  }
  boxes.build_bvhs(threads, [&](size_t i) { return needs_bvh[i] != 0; });
  // Within an object, subtrees all of whose triangles share one of f's vertices hold no
  // candidate (thousands of triangles around one vertex overlap each other's boxes there).
  std::vector<std::vector<std::array<Index, 3>>> common(n);
  if (opts.intra)
    parallel_for(n, threads, [&](size_t i) {
      if (frame.objects[i].num_triangles() > 0 && !intra_known(i))
        common[i] = boxes.bvh(i).node_common_vertices(frame.objects[i].topology->faces);
    });

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
      for (Index f = w.first; f < w.last; ++f) {
        const Face& ff = oi.topology->faces[static_cast<size_t>(f)];
        const auto& node_common = common[static_cast<size_t>(w.i)];
        const TriangleBvh& bvh = boxes.bvh(static_cast<size_t>(w.i));
        const TrianglePlane plane(oi.triangle(f));
        const double size_f = box_size(tb_i[static_cast<size_t>(f)]);
        auto skip = [&](std::int32_t node) {
          return TriangleBvh::adjacent_subtree(node_common[static_cast<size_t>(node)], ff) ||
                 plane.rejects(bvh.node_box(node));
        };
        bvh.query_overlaps(tb_i[static_cast<size_t>(f)], skip, [&](Index g) {
          // Each unordered pair once, from the triangle with the larger box (then the larger
          // id): a sliver's search, pruned by its plane, tests the small triangles under it,
          // rather than each of those finding the sliver.
          const double size_g = box_size(tb_i[static_cast<size_t>(g)]);
          if (size_g > size_f || (size_g == size_f && g >= f)) return;
          if (Adjacency::share_vertex(ff, oi.topology->faces[static_cast<size_t>(g)])) return;
          ++tests[k];
          if (triangles_intersect(oi.triangle(f), oi.triangle(g)))
            hits.push_back(f < g ? IntersectingPair{w.i, f, w.i, g} : IntersectingPair{w.i, g, w.i, f});
        });
      }
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
