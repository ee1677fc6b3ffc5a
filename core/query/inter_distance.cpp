#include "core/query/inter_distance.hpp"

#include "core/broad_phase/object_broad_phase.hpp"
#include "core/broad_phase/triangle_bvh.hpp"
#include "core/geometry/separation_bound.hpp"
#include "core/geometry/triangle_distance.hpp"
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
  /// The pair (own triangle ts, triangle `to` of object o), r from this object's side.
  void take(const TriangleDistanceResult& r, Index o, Index ts, Index to) {
    distance = r.distance;
    other = o;
    tri_self = ts;
    tri_other = to;
    detail = r;
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
  if (best.improved_by(r.distance, j, ts, to)) best.take(r, j, ts, to);
}

/// consider() for a search whose pairs mostly lose: a pair farther than `within` (at least
/// best.distance, or the search's bound where that is smaller: a pair beyond it is not the
/// answer) is dropped as soon as that is certain, and the points are computed only for a pair
/// that improves `best`. Bitwise the same numbers as consider().
void consider_within(const Frame& frame, Index i, Index ts, Index j, Index to, double within, Best& best) {
  const bool i_first = i < j;
  const Triangle ti = frame.objects[static_cast<size_t>(i)].triangle(ts);
  const Triangle tj = frame.objects[static_cast<size_t>(j)].triangle(to);
  const Triangle& first = i_first ? ti : tj;
  const Triangle& second = i_first ? tj : ti;
  TriangleDistanceResult r;
  if (!triangle_distance_within(first, nullptr, second, nullptr, within, r)) return;
  if (!best.improved_by(r.distance, j, ts, to)) return;
  add_closest_points(r, first, nullptr, second, nullptr);
  best.take(i_first ? r : swapped(r), j, ts, to);
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

/// Scratch space of one search, reused by a thread from object to object.
struct SearchScratch {
  TriangleBvh::PairSearch search;
  std::vector<Index> pair_object;               ///< the other object j of each pair searched
  std::vector<std::pair<double, Index>> order;  ///< (squared lower bound, j) of the PNS
  std::vector<double> node_lower;               ///< per node of i's BVH, the smallest D_l
};

/// Searches object i's PNS for its nearest object, updating `best`. Feature-level culling
/// (paper 5.2.1): the triangle pairs of i and each object j whose boxes lie within the bound
/// (the expanded-AABB overlap test), and with Stage II whose lower bounds D_l do not exceed
/// it, found by descending i's and j's triangle BVHs together. All of i's pairs of hierarchies
/// are searched together, best first: triangle pairs are tested in nondecreasing box distance
/// (a leaf pair's triangles at once), so no pair whose boxes are farther apart than the answer
/// is ever tested. Objects join in PNS order (by box distance, a lower bound on their pairs'
/// distances), each once the search has run up to its box distance. A pair (f, g) at distance
/// d <= bound has D_l(f) <= d and D_l(g) <= d (each is at most d from some other object), so
/// the D_l cuts lose nothing. `u` is D_u(O_i) from Stage I or II.
void search_object(const Frame& frame, const FrameBoxes& boxes,
                   const std::vector<Index>& pns, Index i, double u, double slack,
                   const VoronoiBounds* voronoi, Best& best, SearchScratch& scratch,
                   DistanceCounters& counters) {
  const auto ui = static_cast<size_t>(i);
  const auto& tb_i = boxes.triangles[ui];
  const Object& oi = frame.objects[ui];
  const TriangleBvh& bvh_i = boxes.bvh(ui);
  const double* low_i = voronoi ? voronoi->triangle_lower[ui].data() : nullptr;
  if (voronoi) scratch.node_lower = bvh_i.node_min(voronoi->triangle_lower[ui]);
  auto bound = [&] { return std::min(u, best.distance) + slack; };
  // A subtree or triangle of i stays useful while it may still be part of a better pair: its
  // (smallest) D_l is within the bound, and after a contact, its (smallest) id can still win
  // the tie-break.
  auto keep_node = [&](std::size_t p, std::int32_t node) {
    return !(low_i && scratch.node_lower[static_cast<size_t>(node)] > bound()) &&
           !best.contact_prunes(scratch.pair_object[p], bvh_i.node_min_id(node));
  };
  auto keep_triangle = [&](std::size_t p, Index ts) {
    return !(low_i && low_i[ts] > bound()) && !best.contact_prunes(scratch.pair_object[p], ts);
  };
  auto visit = [&](std::size_t p, Index ts, Index to, double) {
    const Index j = scratch.pair_object[p];
    if (voronoi && voronoi->triangle_lower[static_cast<size_t>(j)][static_cast<size_t>(to)] > bound()) return;
    if (best.contact_prunes(j, ts, to)) return;
    // Boxes within the bound, triangles provably farther apart (separation_bound.hpp).
    const Object& oj = frame.objects[static_cast<size_t>(j)];
    if (separation_lower_bound(oi.triangle(ts), oj.triangle(to)) > bound()) {
      ++counters.separation_culled;
      return;
    }
    consider_within(frame, i, ts, j, to, std::min(best.distance, u + slack), best);
    ++counters.exact_tests;
  };
  scratch.search.clear();
  scratch.pair_object.clear();
  // Objects in order of a lower bound on their distance: the box distance, or for boxes that
  // overlap the enclosure bound (enclosure_lower_bound(): objects inside a closed surface, or
  // nested shells, whose boxes contain each other). Pairs then join after the search has run
  // up to their object's bound, which may exceed their box distances: the order of the visits
  // changes, not what is visited within the final bound (each pair stays queued until run()
  // reaches it), and an object whose bound exceeds the answer is skipped whole.
  auto& order = scratch.order;
  order.clear();
  for (Index j : pns) {
    const double box_d2 = box_distance_squared(boxes.objects[ui], boxes.objects[static_cast<size_t>(j)]);
    const double lb = box_d2 > 0 ? 0.0 : enclosure_lower_bound(frame, boxes, i, j);
    order.emplace_back(std::max(box_d2, lb * lb), j);
  }
  std::sort(order.begin(), order.end());
  for (const auto& [dj2, j] : order) {
    const AABB& box_j = boxes.objects[static_cast<size_t>(j)];
    scratch.search.run(bound, keep_node, keep_triangle, visit, dj2);
    const double b = bound();
    if (dj2 > b * b) break;  // sorted by that bound
    if (best.contact_prunes(j)) continue;
    ++counters.object_pns_pairs;
    // The feature-level PNS counter: i's triangles within the bound of j's box.
    for (Index t = 0; t < static_cast<Index>(tb_i.size()); ++t)
      if (!(low_i && low_i[t] > b) && !best.contact_prunes(j, t) &&
          box_distance_squared(tb_i[static_cast<size_t>(t)], box_j) <= b * b)
        ++counters.feature_pns;
    // Box distances raised along the diagonals (FrameBoxes::diagonals()): their rounding, a
    // few 2^-53 of the largest coordinate, is far inside the slack that the bound carries.
    scratch.search.add(bvh_i, boxes.bvh(static_cast<size_t>(j)), b, &boxes.diagonals(frame, ui),
                       &boxes.diagonals(frame, static_cast<size_t>(j)));
    scratch.pair_object.push_back(j);
  }
  scratch.search.run(bound, keep_node, keep_triangle, visit);
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
  Stopwatch sw;
  out.per_object.resize(n);
  boxes.build_bvhs(threads, [](size_t) { return true; });
  std::vector<DistanceCounters> counters(n);
  parallel_for(n, threads, [&](size_t ui) {
    const Index i = static_cast<Index>(ui);
    Best best;
    thread_local SearchScratch scratch;
    // D_u(O_i): Stage II's bound when it ran, else Stage I's.
    const double u = opts.voronoi ? opts.voronoi->object_upper[ui] : stage1.upper_bound[ui];
    // The slack covers the rounding of the distances and bounds of the pairs compared: those of
    // i's pairs with its PNS, whose objects include every object within U_i of i (the PNS has
    // all within U_i plus the frame's slack, which is at least this one). Their coordinates,
    // not the frame's, set it: an object parked far away no longer widens everyone's search.
    double magnitude = boxes.magnitudes[ui];
    for (Index j : stage1.pns[ui]) magnitude = std::max(magnitude, boxes.magnitudes[static_cast<size_t>(j)]);
    const double slack = rounding_slack(magnitude);
    search_object(frame, boxes, stage1.pns[ui], i, u, slack, opts.voronoi, best, scratch,
                  counters[ui]);
    out.per_object[ui] = to_result(i, best);
  });
  for (const auto& c : counters) {
    out.counters.object_pns_pairs += c.object_pns_pairs;
    out.counters.feature_pns += c.feature_pns;
    out.counters.exact_tests += c.exact_tests;
    out.counters.separation_culled += c.separation_culled;
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
