#include "core/query/intra_distance.hpp"

#include "core/broad_phase/triangle_bvh.hpp"
#include "core/geometry/diagonals.hpp"
#include "core/geometry/separation_bound.hpp"
#include "core/mesh/adjacency.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "core/voronoi/self_stage2.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <memory>
#include <tuple>

namespace vproxq {
namespace {

// Vertex pair distances are a few roundings away from exact; widening them by 1e-12 relative
// keeps the 2-ring bound an upper bound of the exact distance (as Stage I does for U_i).
constexpr double kUpperBoundWidening = 1e-12;
// Triangles per work item of the 2-ring bounds' parallel loop.
constexpr std::size_t kBlock = 64;
// Triangles per unit of work of the search (node pairs of at most this many triangles).
constexpr std::int32_t kChunk = 256;
// Ranges of squared box distance in which a unit of work orders its pairs (see below).
constexpr std::size_t kLaterRanges = 8;

/// Distance between triangles f and g of one object, always evaluated with the lower id first,
/// so that f's and g's searches get bitwise the same numbers. Expressed from f's side.
TriangleDistanceResult evaluate(const Object& o, Index f, Index g) {
  return triangle_distance_ordered(o.triangle(f), o.triangle(g), f < g);
}

/// Keeps the smallest (distance, g), r being f's pair with g from f's side: the tie-break
/// shared with the brute force. Returns whether best changed.
bool keep_nearer(IntraTriangleNearest& best, Index g, const TriangleDistanceResult& r) {
  if (std::tie(r.distance, g) >= std::tie(best.distance, best.nearest)) return false;
  best.nearest = g;
  best.distance = r.distance;
  best.points = {r.point_a, r.point_b};
  best.kind = r.kind;
  return true;
}

void consider(const Object& o, Index f, Index g, IntraTriangleNearest& best) {
  keep_nearer(best, g, evaluate(o, f, g));
}

/// Blocks of kBlock triangles over all objects, the work items of the parallel loops, so that
/// many small objects keep the threads as busy as one large one.
class ObjectBlocks {
 public:
  /// blocks(i): how many blocks object i has.
  template <typename Blocks>
  ObjectBlocks(size_t objects, const Blocks& blocks) : first_(objects + 1, 0) {
    for (size_t i = 0; i < objects; ++i) first_[i + 1] = first_[i] + blocks(i);
  }
  static size_t blocks_of(size_t triangles) { return (triangles + kBlock - 1) / kBlock; }

  size_t size() const { return first_.back(); }
  size_t count(size_t object) const { return first_[object + 1] - first_[object]; }
  /// Work item -> (object, block of that object).
  std::pair<size_t, size_t> locate(size_t item) const {
    const auto it = std::upper_bound(first_.begin(), first_.end(), item) - 1;
    const size_t object = static_cast<size_t>(it - first_.begin());
    return {object, item - *it};
  }

 private:
  std::vector<size_t> first_;  ///< first item of each object, and the total
};

/// Fills in the object's minimum from its per-triangle table: smallest (distance, f, g).
void finish_object(IntraObjectDistance& out) {
  for (Index f = 0; f < static_cast<Index>(out.per_triangle.size()); ++f) {
    const IntraTriangleNearest& t = out.per_triangle[static_cast<size_t>(f)];
    if (t.nearest == kNoIndex) continue;
    if (std::tie(t.distance, f, t.nearest) <
        std::tie(out.distance, out.triangles[0], out.triangles[1])) {
      out.distance = t.distance;
      out.triangles = {f, t.nearest};
      out.points = t.points;
    }
  }
}

/// The per-triangle records of one object while the units of its search run in parallel:
/// each evaluated pair is offered to both triangles' records (under a lock per record), which
/// keep the smallest (distance, id) as from their own side (evaluate() gives both sides bitwise
/// the same numbers), so the records end the same whichever thread evaluates which pair.
class SharedPairs {
 public:
  explicit SharedPairs(size_t n) : current_(n), locks_(n) {
    for (auto& c : current_) c.store(kInfinity, std::memory_order_relaxed);
    for (auto& l : locks_) l.store(false, std::memory_order_relaxed);
  }

  /// t's best distance so far (never below its final answer).
  double current(size_t t) const { return current_[t].load(std::memory_order_relaxed); }

  /// Offers t (record `best`) the pair (t, other) at `distance`; full() gives its whole
  /// evaluation from t's side (points included), asked for only when the record takes it.
  template <typename Full>
  void offer(IntraTriangleNearest& best, size_t t, Index other, double distance, const Full& full) {
    Lock lock(locks_[t]);
    if (std::tie(distance, other) >= std::tie(best.distance, best.nearest)) return;
    keep_nearer(best, other, full());
    current_[t].store(distance, std::memory_order_relaxed);
  }

 private:
  /// A spin lock per record: offers are short and rarely contended.
  struct Lock {
    explicit Lock(std::atomic<bool>& f) : flag(f) {
      while (flag.exchange(true, std::memory_order_acquire)) {
      }
    }
    ~Lock() { flag.store(false, std::memory_order_release); }
    std::atomic<bool>& flag;
  };
  std::vector<std::atomic<double>> current_;
  std::vector<std::atomic<bool>> locks_;
};

bool shares_vertex(const Object& o, Index f, Index g) {
  return Adjacency::share_vertex(o.topology->faces[static_cast<size_t>(f)],
                                 o.topology->faces[static_cast<size_t>(g)]);
}

}  // namespace

std::vector<std::vector<double>> ring2_upper_bounds(const Frame& frame, int threads,
                                                    const std::vector<std::uint8_t>* skip) {
  const size_t n_obj = frame.objects.size();
  std::vector<std::vector<double>> out(n_obj);
  for (size_t i = 0; i < n_obj; ++i)
    out[i].assign(static_cast<size_t>(frame.objects[i].num_triangles()), kInfinity);
  const ObjectBlocks blocks(n_obj, [&](size_t i) { return marked(skip, i) ? 0 : ObjectBlocks::blocks_of(out[i].size()); });
  std::vector<const Adjacency*> adj(n_obj, nullptr);
  // The 2-ring vertices are computed and cached on the first frame of a topology: small
  // objects in parallel, each on one thread; then large ones one after the other, each on all
  // threads.
  constexpr size_t kLargeObject = 4096;  // triangles
  parallel_for(n_obj, threads, [&](size_t i) {
    if (out[i].empty() || marked(skip, i)) return;
    adj[i] = &adjacency(*frame.objects[i].topology);
    if (out[i].size() < kLargeObject) adj[i]->prepare_ring2_vertices(1);
  });
  for (size_t i = 0; i < n_obj; ++i)
    if (adj[i] != nullptr && out[i].size() >= kLargeObject) adj[i]->prepare_ring2_vertices(threads);
  parallel_for(blocks.size(), threads, [&](size_t item) {
    const auto [object, block] = blocks.locate(item);
    const size_t i = object;  // a plain variable: lambdas below capture it
    const Object& o = frame.objects[i];
    const Adjacency& a = *adj[i];
    const auto& faces = o.topology->faces;
    for (size_t f = block * kBlock; f < std::min(out[i].size(), (block + 1) * kBlock); ++f) {
      const Face& ff = faces[f];
      double best2 = kInfinity;
      for (Index b : a.ring2_vertices(static_cast<Index>(f)))
        for (Index v : ff)
          best2 = std::min(best2, (o.positions[static_cast<size_t>(v)] -
                                   o.positions[static_cast<size_t>(b)]).squaredNorm());
      out[i][f] = std::sqrt(best2) * (1 + kUpperBoundWidening);
    }
  });
  return out;
}

IntraDistanceOutput intra_object_distance(const Frame& frame, const IntraDistanceOptions& opts) {
  const int threads = std::max(1, opts.threads);
  const FrameBoxes boxes = FrameBoxes::compute(frame, threads);
  return intra_object_distance(frame, boxes, ring2_upper_bounds(frame, threads, opts.skip), opts);
}

IntraDistanceOutput intra_object_distance(const Frame& frame, const FrameBoxes& boxes,
                                          const std::vector<std::vector<double>>& ring2_bound,
                                          const IntraDistanceOptions& opts) {
  Stopwatch sw;
  IntraDistanceOutput out;
  const int threads = std::max(1, opts.threads);
  const size_t n_obj = frame.objects.size();
  out.per_object.resize(n_obj);
  for (size_t i = 0; i < n_obj; ++i) {
    out.per_object[i].object = static_cast<Index>(i);
    if (!marked(opts.skip, i)) out.per_object[i].per_triangle.assign(static_cast<size_t>(frame.objects[i].num_triangles()), {});
  }
  // Per object of at least 2 triangles, what its search reads: the records, each triangle's
  // D_u, the common vertices of each node's triangles, per node the largest reach of its
  // triangles (D_u plus the rounding slack) and, with Stage II, their smallest D_l; and each
  // triangle's parts of the separation bound (SeparationSite) and of the exact test
  // (PreparedTriangleParts), computed once instead of in each of its candidate pairs
  // (docs/algorithms.md, "Exactness").
  struct ObjectSearch {
    std::unique_ptr<SharedPairs> pairs;
    std::vector<double> upper;
    std::vector<std::array<Index, 3>> common;
    std::vector<double> reach, node_lower;
    std::vector<SeparationSite> sites;  ///< per triangle: its part of separation_lower_bound()
    std::vector<PreparedTriangleParts> prepared;  ///< per triangle: its part of triangle_distance()
    const HierarchyDiagonals* diagonals = nullptr;  ///< FrameBoxes::diagonals()
    double slack = 0;
  };
  std::vector<ObjectSearch> search(n_obj);
  const SelfVoronoiBounds* voronoi = opts.voronoi;
  // Units of work: per object, the node pairs of at most kChunk triangles that the descent
  // below goes through first (TriangleBvh::self_pairs_below()).
  struct Task {
    size_t object;
    TriangleBvh::NodePair pair;
  };
  std::vector<std::vector<TriangleBvh::NodePair>> units(n_obj);
  // Whether the descent enters the node pair (a, b) of object i: not when every pair of their
  // triangles shares a vertex (a vertex common to both nodes' triangles), else when a triangle
  // of one side may need a triangle of the other: the nodes' boxes (and their projections on
  // the diagonals, Diagonals: the gap along one divided by sqrt(3), when larger) within the
  // first side's reach, and (Stage II) the second side's smallest D_l too. The projections
  // are off by a few 2^-53 M (M: the object's largest coordinate), far below the rounding
  // slack in the reach, so a pair passed over is farther apart than its bounds.
  auto enter = [&](size_t i, std::int32_t a, std::int32_t b) {
    const ObjectSearch& s = search[i];
    const auto& ca = s.common[static_cast<size_t>(a)];
    if (a == b) return ca[0] == kNoIndex;
    if (TriangleBvh::adjacent_subtree(ca, s.common[static_cast<size_t>(b)])) return false;
    const TriangleBvh& bvh = boxes.bvh(i);
    const double d2 = raised_distance_squared(box_distance_squared(bvh.node_box(a), bvh.node_box(b)),
                                              s.diagonals->nodes[static_cast<size_t>(a)],
                                              s.diagonals->nodes[static_cast<size_t>(b)]);
    const double ra = s.reach[static_cast<size_t>(a)], rb = s.reach[static_cast<size_t>(b)];
    const bool lower = !s.node_lower.empty();
    return (d2 <= ra * ra && (!lower || s.node_lower[static_cast<size_t>(b)] <= ra)) ||
           (d2 <= rb * rb && (!lower || s.node_lower[static_cast<size_t>(a)] <= rb));
  };
  parallel_for(n_obj, threads, [&](size_t i) {
    const size_t n = out.per_object[i].per_triangle.size();
    if (n < 2) return;  // no pairs
    ObjectSearch& s = search[i];
    const TriangleBvh& bvh = boxes.bvh(i);
    // Every distance compared here is between two triangles of object i: its own magnitude
    // bounds their rounding (an object far away elsewhere in the scene does not matter).
    s.slack = rounding_slack(boxes.magnitudes[i]);
    s.pairs = std::make_unique<SharedPairs>(n);
    s.common = bvh.node_common_vertices(frame.objects[i].topology->faces);
    s.sites.resize(n);
    s.prepared.resize(n);
    s.diagonals = &boxes.diagonals(frame, i);
    // D_u(t): the 2-ring bound, or Stage II's (which already includes it) when smaller.
    s.upper = ring2_bound[i];
    if (voronoi)
      for (size_t t = 0; t < n; ++t) s.upper[t] = std::min(s.upper[t], voronoi->triangle_upper[i][t]);
    std::vector<double> reach(n);
    for (size_t t = 0; t < n; ++t) reach[t] = s.upper[t] + s.slack;
    s.reach = bvh.node_max(reach);
    if (voronoi) s.node_lower = bvh.node_min(voronoi->triangle_lower[i]);
    units[i] = bvh.self_pairs_below(kChunk, [&](std::int32_t a, std::int32_t b) { return enter(i, a, b); });
  });
  // Each triangle's parts of the separation bound and of the exact test, computed once instead
  // of in each of its pairs (about 8 per triangle), in blocks over all objects.
  const ObjectBlocks site_blocks(n_obj, [&](size_t i) { return ObjectBlocks::blocks_of(search[i].sites.size()); });
  parallel_for(site_blocks.size(), threads, [&](size_t item) {
    const auto [i, block] = site_blocks.locate(item);
    ObjectSearch& s = search[i];
    for (size_t t = block * kBlock; t < std::min(s.sites.size(), (block + 1) * kBlock); ++t) {
      const Triangle tri = frame.objects[i].triangle(static_cast<Index>(t));
      s.sites[t] = separation_site(tri);
      s.prepared[t] = parts_of(prepare_triangle(tri));
    }
  });
  std::vector<Task> tasks;
  for (size_t i = 0; i < n_obj; ++i)
    for (const auto& pair : units[i]) tasks.push_back({i, pair});

  // Each unordered pair of non-adjacent triangles (f, g) of an entered pair of leaves is a
  // candidate for f when their boxes (and diagonals, as above) lie within f's bound,
  // min(D_u(f), f's best so far) + slack (and, with Stage II, D_l(g) does too: a pair at
  // distance d within it has D_l(g) <= SD(g) <= d), and likewise for g. A side's candidate
  // is culled when the pair's separation bound exceeds its bound; a pair that is still a
  // candidate for either side is evaluated once and offered to both. So every triangle's
  // nearest pair is evaluated: at every level its boxes lie within the triangle's bound, which
  // never drops below that pair's distance.
  std::vector<DistanceCounters> counters(tasks.size());
  std::vector<std::vector<IntersectingPair>> hits(tasks.size());
  parallel_for(tasks.size(), threads, [&](size_t k) {
    const size_t i = tasks[k].object;
    const Object& o = frame.objects[i];
    const ObjectSearch& s = search[i];
    SharedPairs& pairs = *s.pairs;
    IntraObjectDistance& res = out.per_object[i];
    const double* lower = voronoi ? voronoi->triangle_lower[i].data() : nullptr;
    DistanceCounters& c = counters[k];
    const double* upper = s.upper.data();
    const SeparationSite* sites = s.sites.data();
    const auto bound = [&](size_t t) { return std::min(upper[t], pairs.current(t)) + s.slack; };
    // The candidate pair (f, g), f < g, whose boxes are d2 apart (squared).
    auto try_pair = [&](Index f, Index g, double d2) {
      const size_t uf = static_cast<size_t>(f), ug = static_cast<size_t>(g);
      const double bf = bound(uf), bg = bound(ug);
      bool for_f = d2 <= bf * bf, for_g = d2 <= bg * bg;
      if (!for_f && !for_g) return;
      c.intra_candidates += std::uint64_t{for_f} + std::uint64_t{for_g};
      if (lower) {
        if (for_f && lower[ug] > bf) {
          for_f = false;
          ++c.intra_voronoi_culled;
        }
        if (for_g && lower[uf] > bg) {
          for_g = false;
          ++c.intra_voronoi_culled;
        }
        if (!for_f && !for_g) return;
      }
      // Boxes within the bound, triangles provably farther apart (separation_bound.hpp).
      const double separation = separation_lower_bound(o.triangle(f), sites[static_cast<size_t>(f)], o.triangle(g),
                                                       sites[static_cast<size_t>(g)]);
      if (for_f && separation > bf) {
        for_f = false;
        ++c.intra_separation_culled;
      }
      if (for_g && separation > bg) {
        for_g = false;
        ++c.intra_separation_culled;
      }
      if (!for_f && !for_g) return;
      ++c.intra_exact_tests;
      if (for_f && for_g) ++c.intra_reused;  // one evaluation serves both sides
      // evaluate(o, f, g) (f < g), its points computed only when a record takes the pair:
      // most evaluated pairs improve neither side. A pair farther than the bound of each side
      // it is a candidate for is the nearest of neither (a bound never drops below the
      // computed distance of its triangle's nearest pair; on the other side the pair lies
      // beyond the bound already), so its exact test stops as soon as that is certain, and it
      // is not offered.
      const Triangle tf = o.triangle(f), tg = o.triangle(g);
      const PreparedTriangle pf = prepared_from_parts(tf, s.prepared[uf]);
      const PreparedTriangle pg = prepared_from_parts(tg, s.prepared[ug]);
      const double within = std::max(for_f ? bf : 0.0, for_g ? bg : 0.0);
      TriangleDistanceResult r;
      if (!triangle_distance_within(tf, &pf, tg, &pg, within, r)) return;
      if (r.kind == TriangleDistanceCase::Intersecting) {
        const Index io = static_cast<Index>(i);
        hits[k].push_back({io, f, io, g});
      }
      bool have_points = false;
      auto full = [&]() -> const TriangleDistanceResult& {
        if (!have_points) add_closest_points(r, tf, &pf, tg, &pg);
        have_points = true;
        return r;
      };
      pairs.offer(res.per_triangle[uf], uf, g, r.distance, full);
      pairs.offer(res.per_triangle[ug], ug, f, r.distance, [&] { return swapped(full()); });
    };
    // Pairs whose boxes overlap are considered as the descent meets them, the others after it,
    // nearer boxes first (by a counting sort into kLaterRanges equal ranges of squared box
    // distance): so a triangle's bound comes down on its near pairs before its far ones are
    // tried, as in a search per triangle nearest first. In the descent's order alone, skirt
    // and cloth-ball ran 45% and 56% more exact tests than that search.
    struct Later {
      double d2;
      Index f, g;
    };
    thread_local std::vector<Later> later, sorted;
    thread_local std::vector<std::uint32_t> first;
    later.clear();
    double farthest = 0;
    boxes.bvh(i).descend_self(tasks[k].pair, [&](std::int32_t a, std::int32_t b) { return enter(i, a, b); },
                              [&](Index t, Index u, const AABB& bt, const AABB& bu) {
      const Index f = std::min(t, u), g = std::max(t, u);
      const double bf = bound(static_cast<size_t>(f)), bg = bound(static_cast<size_t>(g));
      const double reach2 = std::max(bf * bf, bg * bg);
      // The diagonals only raise the boxes' distance: a pair beyond both bounds by its boxes
      // is passed over without them.
      const double box_d2 = box_distance_squared(bt, bu);
      if (box_d2 > reach2) return;
      const double d2 = raised_distance_squared(box_d2, s.diagonals->triangles[static_cast<size_t>(f)],
                                                s.diagonals->triangles[static_cast<size_t>(g)]);
      if (d2 > reach2 || shares_vertex(o, f, g)) return;
      if (d2 > 0) {
        later.push_back({d2, f, g});
        farthest = std::max(farthest, d2);
      } else {
        try_pair(f, g, d2);
      }
    });
    // Clamped in double: with a subnormal `farthest` the scale may be infinite.
    const double scale = kLaterRanges / farthest, last = kLaterRanges - 1;
    auto range_of = [&](double d2) { return static_cast<std::size_t>(std::min(last, d2 * scale)); };
    first.assign(kLaterRanges + 1, 0);
    for (const Later& l : later) ++first[range_of(l.d2) + 1];
    for (std::size_t r = 0; r < kLaterRanges; ++r) first[r + 1] += first[r];
    sorted.resize(later.size());
    for (const Later& l : later) sorted[first[range_of(l.d2)]++] = l;
    for (const Later& l : sorted) try_pair(l.f, l.g, l.d2);
  });
  for (const auto& c : counters) {
    out.counters.intra_candidates += c.intra_candidates;
    out.counters.intra_voronoi_culled += c.intra_voronoi_culled;
    out.counters.intra_separation_culled += c.intra_separation_culled;
    out.counters.intra_reused += c.intra_reused;
    out.counters.intra_exact_tests += c.intra_exact_tests;
  }
  for (const auto& h : hits) out.intersecting.insert(out.intersecting.end(), h.begin(), h.end());
  std::sort(out.intersecting.begin(), out.intersecting.end());
  out.intersecting.erase(std::unique(out.intersecting.begin(), out.intersecting.end()), out.intersecting.end());
  parallel_for(n_obj, threads, [&](size_t i) { finish_object(out.per_object[i]); });
  out.exact_ms = sw.elapsed_ms();
  return out;
}

IntraDistanceOutput intra_object_distance_brute_force(const Frame& frame, int threads) {
  IntraDistanceOutput out;
  out.per_object.resize(frame.objects.size());
  for (size_t i = 0; i < frame.objects.size(); ++i) {
    const Object& o = frame.objects[i];
    IntraObjectDistance& res = out.per_object[i];
    res.object = static_cast<Index>(i);
    const Index n = o.num_triangles();
    res.per_triangle.assign(static_cast<size_t>(n), {});
    parallel_for(static_cast<size_t>(n), std::max(1, threads), [&](size_t uf) {
      const Index f = static_cast<Index>(uf);
      for (Index g = 0; g < n; ++g)
        if (g != f && !shares_vertex(o, f, g)) consider(o, f, g, res.per_triangle[uf]);
    });
    for (Index f = 0; f < n; ++f)
      for (Index g = 0; g < n; ++g)
        if (g != f && !shares_vertex(o, f, g)) ++out.counters.intra_exact_tests;
    finish_object(res);
  }
  out.counters.intra_candidates = out.counters.intra_exact_tests;
  return out;
}

IntraDistanceOutput intra_object_distance_sorted_scan(const Frame& frame, int threads) {
  IntraDistanceOutput out;
  const FrameBoxes boxes = FrameBoxes::compute(frame, std::max(1, threads));
  const double slack = rounding_slack(boxes.magnitude);
  out.per_object.resize(frame.objects.size());
  for (size_t i = 0; i < frame.objects.size(); ++i) {
    const Object& o = frame.objects[i];
    IntraObjectDistance& res = out.per_object[i];
    res.object = static_cast<Index>(i);
    const size_t n = static_cast<size_t>(o.num_triangles());
    res.per_triangle.assign(n, {});
    const auto& tb = boxes.triangles[i];
    std::vector<std::uint64_t> tests(n, 0);
    parallel_for(n, std::max(1, threads), [&](size_t uf) {
      std::vector<std::pair<double, Index>> order;
      order.reserve(n);
      for (size_t g = 0; g < n; ++g) order.emplace_back(box_distance_squared(tb[uf], tb[g]), static_cast<Index>(g));
      std::sort(order.begin(), order.end());
      IntraTriangleNearest& best = res.per_triangle[uf];
      for (const auto& [d2, g] : order) {
        const double b = best.distance + slack;  // box distance <= triangle distance
        if (d2 > b * b) break;
        if (g == static_cast<Index>(uf) || shares_vertex(o, static_cast<Index>(uf), g)) continue;
        consider(o, static_cast<Index>(uf), g, best);
        ++tests[uf];
      }
    });
    for (auto t : tests) out.counters.intra_exact_tests += t;
    finish_object(res);
  }
  out.counters.intra_candidates = out.counters.intra_exact_tests;
  return out;
}

}  // namespace vproxq
