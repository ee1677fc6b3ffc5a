#include "core/query/inter_distance.hpp"

#include "core/broad_phase/object_broad_phase.hpp"
#include "core/broad_phase/triangle_bvh.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "core/voronoi/stage2.hpp"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <tuple>

namespace vproxq {
namespace {

/// The running answer for one object while its PNS is searched.
struct Best {
  double distance = kInfinity;
  Index other = kNoIndex;
  Index tri_self = kNoIndex;
  Index tri_other = kNoIndex;
  TriangleDistanceResult detail;

  /// Lexicographic order (distance, other object, own triangle, other triangle): the
  /// deterministic tie-break shared with the brute force.
  bool improved_by(double d, Index o, Index ts, Index to) const {
    return std::tie(d, o, ts, to) < std::tie(distance, other, tri_self, tri_other);
  }

  /// Once the answer is a contact (distance 0), no pair can be strictly closer, so only a
  /// pair with smaller ids can still win the tie-break: (o, ts, to) lexicographically before
  /// the current ones. Pairs failing this need no exact test.
  bool contact_prunes(Index o) const { return distance == 0 && o > other; }
  bool contact_prunes(Index o, Index ts) const {
    return distance == 0 && (o > other || (o == other && ts > tri_self));
  }
  bool contact_prunes(Index o, Index ts, Index to) const {
    return distance == 0 && std::tie(o, ts, to) > std::tie(other, tri_self, tri_other);
  }
};

/// Distance between triangle ts of object i and triangle to of object j, always evaluated
/// with the lower object id first so that (i, j) and (j, i) give bitwise the same numbers.
/// The result is expressed from i's side (point_a and feature_a on i).
TriangleDistanceResult evaluate(const Frame& frame, Index i, Index ts, Index j, Index to) {
  const Object& oi = frame.objects[static_cast<size_t>(i)];
  const Object& oj = frame.objects[static_cast<size_t>(j)];
  return triangle_distance_ordered(oi.triangle(ts), oj.triangle(to), i < j);
}

void consider(const Frame& frame, Index i, Index ts, Index j, Index to, Best& best) {
  const TriangleDistanceResult r = evaluate(frame, i, ts, j, to);
  if (best.improved_by(r.distance, j, ts, to)) {
    best.distance = r.distance;
    best.other = j;
    best.tri_self = ts;
    best.tri_other = to;
    best.detail = r;
  }
}

InterObjectDistance to_result(Index i, const Best& best) {
  InterObjectDistance out;
  out.object = i;
  if (best.other == kNoIndex) return out;
  out.nearest_object = best.other;
  out.distance = best.distance;
  out.triangles = {best.tri_self, best.tri_other};
  out.points = {best.detail.point_a, best.detail.point_b};
  out.kind = best.detail.kind;
  return out;
}

/// Searches the triangle pairs of objects i and j within the current bound, updating `best`:
/// triangles of i near j's box (nearest first) each query j's triangle BVH with their box
/// expanded by the bound (paper 5.2.1's expanded-AABB overlap test), and the exact test runs
/// on every pair that passes. `u` is D_u(O_i) from Stage I or II.
void search_pair(const Frame& frame, const FrameBoxes& boxes, const TriangleBvh& bvh_j, Index i,
                 Index j, double u, double slack, const VoronoiBounds* voronoi, Best& best,
                 std::vector<std::pair<double, Index>>& self_tris, DistanceCounters& counters) {
  auto bound = [&] { return std::min(u, best.distance) + slack; };
  const auto& tb_i = boxes.triangles[static_cast<size_t>(i)];
  const AABB& box_j = boxes.objects[static_cast<size_t>(j)];
  // Feature-level culling: triangles of i near j's box and, with Stage II, whose lower bound
  // D_l does not exceed the bound. A pair (f, g) at distance d <= bound has D_l(f) <= d and
  // D_l(g) <= d (each is at most d from some other object), so no answer is culled.
  const double* low_i = voronoi ? voronoi->triangle_lower[static_cast<size_t>(i)].data() : nullptr;
  const double* low_j = voronoi ? voronoi->triangle_lower[static_cast<size_t>(j)].data() : nullptr;
  const double b0 = bound();
  self_tris.clear();
  for (Index t = 0; t < static_cast<Index>(tb_i.size()); ++t) {
    if (low_i && low_i[t] > b0) continue;
    const double d2 = box_distance_squared(tb_i[static_cast<size_t>(t)], box_j);
    if (d2 <= b0 * b0) self_tris.emplace_back(d2, t);
  }
  counters.feature_pns += self_tris.size();
  std::sort(self_tris.begin(), self_tris.end());
  for (const auto& [d2, ts] : self_tris) {
    const double b = bound();
    if (d2 > b * b) break;
    if (best.contact_prunes(j, ts)) continue;
    bvh_j.query(tb_i[static_cast<size_t>(ts)], bound, [&](Index to, double) {
      if (low_j && low_j[to] > bound()) return;
      if (best.contact_prunes(j, ts, to)) return;
      consider(frame, i, ts, j, to, best);
      ++counters.exact_tests;
    });
  }
}

}  // namespace

InterDistanceOutput inter_object_distance(const Frame& frame, const InterDistanceOptions& opts) {
  Stopwatch sw;
  const int threads = std::max(1, opts.threads);
  const FrameBoxes boxes = FrameBoxes::compute(frame, threads);
  const ObjectBroadPhase stage1 = object_broad_phase(frame, boxes, threads);
  const double aabb_ms = sw.elapsed_ms();
  InterDistanceOutput out = inter_object_distance(frame, boxes, stage1, opts);
  out.aabb_ms += aabb_ms;
  return out;
}

InterDistanceOutput inter_object_distance(const Frame& frame, const FrameBoxes& boxes,
                                          const ObjectBroadPhase& stage1,
                                          const InterDistanceOptions& opts) {
  InterDistanceOutput out;
  const size_t n = frame.objects.size();
  const int threads = std::max(1, opts.threads);
  const double slack = rounding_slack(boxes.magnitude);
  Stopwatch sw;
  out.per_object.resize(n);
  std::vector<TriangleBvh> bvhs(n);
  parallel_for(n, threads, [&](size_t i) { bvhs[i].build(boxes.triangles[i]); });
  std::vector<DistanceCounters> counters(n);
  parallel_for(n, threads, [&](size_t ui) {
    const Index i = static_cast<Index>(ui);
    Best best;
    std::vector<std::pair<double, Index>> self_tris;
    // D_u(O_i): Stage II's bound when it ran, else Stage I's.
    const double u = opts.voronoi ? opts.voronoi->object_upper[ui] : stage1.upper_bound[ui];
    for (Index j : stage1.pns[ui]) {
      const double bound = std::min(u, best.distance) + slack;
      if (box_distance_squared(boxes.objects[ui], boxes.objects[static_cast<size_t>(j)]) >
          bound * bound)
        break;  // PNS is sorted by box distance
      if (best.contact_prunes(j)) continue;
      ++counters[ui].object_pns_pairs;
      search_pair(frame, boxes, bvhs[static_cast<size_t>(j)], i, j, u, slack, opts.voronoi, best,
                  self_tris, counters[ui]);
    }
    out.per_object[ui] = to_result(i, best);
  });
  for (const auto& c : counters) {
    out.counters.object_pns_pairs += c.object_pns_pairs;
    out.counters.feature_pns += c.feature_pns;
    out.counters.exact_tests += c.exact_tests;
  }
  out.exact_ms = sw.elapsed_ms();
  return out;
}

InterDistanceOutput inter_object_distance_brute_force(const Frame& frame) {
  InterDistanceOutput out;
  const Index n = static_cast<Index>(frame.objects.size());
  out.per_object.resize(static_cast<size_t>(n));
  for (Index i = 0; i < n; ++i) {
    Best best;
    for (Index j = 0; j < n; ++j) {
      if (j == i) continue;
      for (Index ts = 0; ts < frame.objects[static_cast<size_t>(i)].num_triangles(); ++ts)
        for (Index to = 0; to < frame.objects[static_cast<size_t>(j)].num_triangles(); ++to) {
          consider(frame, i, ts, j, to, best);
          ++out.counters.exact_tests;
        }
    }
    out.per_object[static_cast<size_t>(i)] = to_result(i, best);
  }
  out.counters.feature_pns = out.counters.exact_tests;
  return out;
}

}  // namespace vproxq
