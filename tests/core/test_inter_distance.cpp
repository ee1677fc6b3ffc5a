// Inter-object N-body distance: Stage I + Stage III against the all-pairs brute force.
#include "core/broad_phase/object_broad_phase.hpp"
#include "core/broad_phase/triangle_bvh.hpp"
#include "core/geometry/point_triangle.hpp"
#include "core/query/inter_distance.hpp"
#include "support/expect_same.hpp"
#include "support/random_scene.hpp"
#include "support/self_meshes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <numeric>
#include <set>
#include <tuple>

namespace vproxq {
namespace {

using test::make_blob;
using test::make_random_frame;
using test::make_soup;
using test::Rng;

/// The distance between objects i and j of a frame, over all their triangle pairs.
double object_distance(const Frame& frame, size_t i, size_t j) {
  double d = kInfinity;
  for (Index a = 0; a < frame.objects[i].num_triangles(); ++a)
    for (Index b = 0; b < frame.objects[j].num_triangles(); ++b)
      d = std::min(d, triangle_distance(frame.objects[i].triangle(a), frame.objects[j].triangle(b)).distance);
  return d;
}

TEST(InterDistance, RandomBlobScenesEqualBruteForce) {
  std::uint64_t separated = 0;
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    const int n = 2 + static_cast<int>(seed % 9);
    const double spread = 0.5 + 0.6 * static_cast<double>(seed % 5);  // from overlapping to apart
    const Frame frame = make_random_frame(seed, n, spread, 1);
    const auto ref = inter_object_distance_brute_force(frame);
    for (int threads : {1, 3}) {
      const auto got = inter_object_distance(frame, {threads});
      test::expect_same_inter(got, ref, "seed " + std::to_string(seed) + " threads " + std::to_string(threads));
      EXPECT_LE(got.counters.exact_tests, ref.counters.exact_tests);
      separated += got.counters.separation_culled;
    }
  }
  // Pairs whose boxes are within the bound but whose triangles are not are skipped untested.
  EXPECT_GT(separated, 0u);
}

TEST(InterDistance, TriangleSoupsWithManyIntersectionsEqualBruteForce) {
  for (std::uint64_t seed = 100; seed < 106; ++seed) {
    Rng rng(seed);
    Frame frame;
    for (int i = 0; i < 6; ++i)
      frame.objects.push_back(make_soup(rng, Vec3{rng.uniform(0, 2), rng.uniform(0, 2), 0}, 0.6, 0.4,
                                        30, "soup" + std::to_string(i)));
    const auto ref = inter_object_distance_brute_force(frame);
    test::expect_same_inter(inter_object_distance(frame, {2}), ref, "soup seed " + std::to_string(seed));
  }
}

TEST(InterDistance, LargeCoordinateOffsetEqualsBruteForce) {
  Frame frame = make_random_frame(7, 6, 2.0, 1);
  for (auto& o : frame.objects)
    for (auto& p : o.positions) p += Vec3(1e6, -1e6, 1e6);
  test::expect_same_inter(inter_object_distance(frame, {2}), inter_object_distance_brute_force(frame), "offset 1e6");
}

TEST(InterDistance, AFarAwayObjectDoesNotWidenTheOthersSearch) {
  // The rounding slack of an object's search comes from the coordinates of the objects within
  // its bound: a blob parked at 1e12 (whose slack is 100 units) must not turn the search among
  // the objects near the origin, all within 100 of each other, into all pairs.
  Rng rng(11);
  const Frame near = make_random_frame(3, 8, 1.5, 1);
  Frame with_far = near;
  with_far.objects.push_back(make_blob(rng, Vec3::Constant(1e12), 1.0, 1, 0.2, "far"));
  const auto ref = inter_object_distance_brute_force(with_far);
  const auto got = inter_object_distance(with_far, {2});
  test::expect_same_inter(got, ref, "blobs and a far blob");
  // Only the far blob's own search may test more than the near ones do among themselves: at
  // most every pair of its triangles with the triangles near the origin.
  const auto alone = inter_object_distance(near, {2});
  std::uint64_t near_triangles = 0;
  for (const auto& o : near.objects) near_triangles += static_cast<std::uint64_t>(o.num_triangles());
  const auto far_triangles = static_cast<std::uint64_t>(with_far.objects.back().num_triangles());
  EXPECT_LE(got.counters.exact_tests, alone.counters.exact_tests + far_triangles * near_triangles);
  EXPECT_LT(got.counters.exact_tests, ref.counters.exact_tests / 4);
}

TEST(InterDistance, TiesGoToTheSmallestIds) {
  // Object 0 in the middle, objects 1 and 2 are mirror images at exactly the same distance;
  // object 3 is a copy of 2 (same distance to 0, larger id). Nearest of 0 must be 1.
  Rng rng(3);
  Object mid = make_blob(rng, Vec3(0, 0, 0), 1.0, 0, 0.0, "mid");
  Object right = make_blob(rng, Vec3(3, 0, 0), 1.0, 0, 0.0, "right");
  Object left = make_blob(rng, Vec3(-3, 0, 0), 1.0, 0, 0.0, "left");
  Object copy = right;
  copy.name = "copy";
  Frame frame;
  frame.objects = {mid, left, right, copy};
  const auto got = inter_object_distance(frame, {2});
  test::expect_same_inter(got, inter_object_distance_brute_force(frame), "ties");
  EXPECT_EQ(got.per_object[0].nearest_object, 1);
  EXPECT_DOUBLE_EQ(got.per_object[0].distance, 1.0);
  EXPECT_EQ(got.per_object[2].nearest_object, 3);  // identical copies: distance 0
  EXPECT_EQ(got.per_object[2].distance, 0.0);
}

TEST(InterDistance, AContactBeatsAGapBelowRounding) {
  // Found by an independent exact oracle: A and B both cross C, and B's apex is 8.9e-18 from A
  // (an exact rational computation), a gap the coordinate differences round away. That
  // computed 0 used to win the tie-break by the smaller id, so A and B were each other's
  // nearest object at "distance 0" while the intersecting pairs listed (A, C) and (B, C).
  // Distance 0 now means a contact only.
  const Object a = test::make_object({Vec3(0.0, 0.0, 0.6), Vec3(1.0, 0.0, -0.57), Vec3(0.0, 1.0, -0.53)},
                                     {{0, 1, 2}}, "A");
  const Object b = test::make_object({Vec3(0.12, 0.25, 0.1771), Vec3(0.01999999999999999, 0.15, 0.6771),
                                      Vec3(0.32, 0.2, 0.6771), Vec3(0.12, 0.45, 0.6771)},
                                     {{0, 1, 2}, {0, 2, 3}, {0, 3, 1}, {1, 3, 2}}, "B");
  const Object c = test::make_object({Vec3(0.0, 0.0, 0.3), Vec3(1.0, 0.0, 0.91), Vec3(0.0, 1.0, 0.99)},
                                     {{0, 1, 2}}, "C");
  Frame frame;
  frame.objects = {a, b, c};
  const auto got = inter_object_distance(frame, {1});
  test::expect_same_inter(got, inter_object_distance_brute_force(frame), "contact and rounded gap");
  EXPECT_EQ(got.per_object[0].nearest_object, 2);
  EXPECT_EQ(got.per_object[0].distance, 0.0);
  EXPECT_EQ(got.per_object[0].kind, TriangleDistanceCase::Intersecting);
  EXPECT_EQ(got.per_object[1].nearest_object, 2);  // B crosses C too (and was given A)
  EXPECT_EQ(got.per_object[1].distance, 0.0);
  const double gap = object_distance(frame, 0, 1);
  EXPECT_GT(gap, 0.0);
  EXPECT_LT(gap, 1e-15);
}

TEST(InterDistance, SingleObjectAndEmptyObjectsHaveNoNearest) {
  Rng rng(5);
  Frame one;
  one.objects.push_back(make_blob(rng, Vec3::Zero(), 1.0, 1, 0.1, "alone"));
  auto got = inter_object_distance(one, {1});
  ASSERT_EQ(got.per_object.size(), 1u);
  EXPECT_FALSE(got.per_object[0].has_nearest());
  EXPECT_EQ(got.per_object[0].distance, kInfinity);

  Object empty;
  empty.name = "empty";
  empty.topology = std::make_shared<Topology>();
  one.objects.push_back(empty);
  one.objects.push_back(make_blob(rng, Vec3(5, 0, 0), 1.0, 1, 0.1, "other"));
  got = inter_object_distance(one, {2});
  test::expect_same_inter(got, inter_object_distance_brute_force(one), "with empty object");
  EXPECT_FALSE(got.per_object[1].has_nearest());
  EXPECT_EQ(got.per_object[0].nearest_object, 2);
}

TEST(TriangleBvh, QueryOverlapsSkipsOnlyWhatNodeUnionsExclude) {
  // Two box sets per triangle: the hierarchy's own and a second (as CCD's boxes at the ends of
  // a step). Pruning subtrees whose union of second boxes misses a second probe must still
  // visit, once, every triangle whose first box overlaps the probe and whose second box meets
  // the second probe, and nothing whose first box misses the probe.
  const Frame frame = make_random_frame(11, 3, 1.0, 1);
  const FrameBoxes boxes = FrameBoxes::compute(frame, 1);
  const auto& first = boxes.triangles[0];
  std::vector<AABB> second(first.size());
  Rng rng(5);
  for (size_t t = 0; t < first.size(); ++t) {
    const Vec3 shift = rng.vec3(-0.5, 0.5);
    second[t] = {first[t].lo + shift, first[t].hi + shift};
  }
  TriangleBvh bvh;
  bvh.build(first);
  const std::vector<AABB> unions = bvh.node_unions(second);
  std::uint64_t pruned_visits_saved = 0;
  for (size_t p = 0; p < first.size(); p += 5) {
    const AABB& probe = first[p];
    const AABB& probe2 = second[(p * 7) % second.size()];
    std::multiset<Index> got, all;
    bvh.query_overlaps(probe, [&](std::int32_t node) {
      return box_distance_squared(unions[static_cast<size_t>(node)], probe2) > 0.0;
    }, [&](Index t) { got.insert(t); });
    bvh.query_overlaps(probe, [](std::int32_t) { return false; }, [&](Index t) { all.insert(t); });
    for (Index t = 0; t < static_cast<Index>(first.size()); ++t) {
      const bool overlaps = box_distance_squared(probe, first[static_cast<size_t>(t)]) == 0.0;
      EXPECT_EQ(all.count(t), overlaps ? 1u : 0u) << "triangle " << t;
      if (overlaps && box_distance_squared(probe2, second[static_cast<size_t>(t)]) == 0.0) {
        EXPECT_EQ(got.count(t), 1u) << "pruned away triangle " << t;
      }
      if (!overlaps) {
        EXPECT_EQ(got.count(t), 0u) << "triangle " << t;
      }
    }
    pruned_visits_saved += all.size() - got.size();
  }
  EXPECT_GT(pruned_visits_saved, 0u);  // the pruning did prune
}

TEST(TriangleBvh, AnyWithinAgreesWithAScanOfTheBoxes) {
  // Stage II's sampling filter: whether some triangle box lies within a bound of a query box
  // (points and boxes, near and far, bounds from 0 up).
  const Frame frame = make_random_frame(13, 2, 2.0, 2);
  const FrameBoxes boxes = FrameBoxes::compute(frame, 1);
  const auto& mine = boxes.triangles[0];
  TriangleBvh bvh;
  bvh.build(mine);
  Rng rng(17);
  int yes = 0, no = 0;
  for (int q = 0; q < 3000; ++q) {
    AABB query;
    const AABB& around = boxes.objects[0];
    Vec3 p;
    for (int k = 0; k < 3; ++k) p[k] = rng.uniform(around.lo[k] - 0.5, around.hi[k] + 0.5);
    query.extend(p);
    if (q % 2) query.extend(p + rng.vec3(0, 0.3));
    const double bound = q % 7 == 0 ? 0.0 : rng.uniform(0, 1.0);
    bool want = false;
    for (const AABB& b : mine) want = want || box_distance_squared(query, b) <= bound * bound;
    ASSERT_EQ(bvh.any_within(query, bound), want) << "query " << q;
    (want ? yes : no)++;
  }
  EXPECT_GT(yes, 300);
  EXPECT_GT(no, 300);
  EXPECT_FALSE(TriangleBvh().any_within(boxes.objects[0], 1e300));
}

TEST(TriangleBvh, ParallelBuildGivesTheSameHierarchy) {
  // Built on several threads, a hierarchy has the same nodes at the same places as built on
  // one (the searches' visiting order, and so their counters, depend on it): the boxes of
  // two blobs (8,704 triangles), and some of their first ones.
  const Frame frame = make_random_frame(5, 1, 1.0, 5);
  const FrameBoxes boxes = FrameBoxes::compute(frame, 1);
  std::vector<AABB> all = boxes.triangles[0];
  const Frame small = make_random_frame(6, 1, 1.0, 3);
  const FrameBoxes small_boxes = FrameBoxes::compute(small, 1);
  all.insert(all.end(), small_boxes.triangles[0].begin(), small_boxes.triangles[0].end());
  ASSERT_EQ(all.size(), 8704u);
  for (size_t n : {all.size(), all.size() - 1, size_t{4099}, size_t{17}, size_t{5}, size_t{1}}) {
    const std::vector<AABB> part(all.begin(), all.begin() + static_cast<std::ptrdiff_t>(n));
    TriangleBvh one;
    one.build(part);
    for (int threads : {2, 3, 4, 7}) {
      SCOPED_TRACE("n " + std::to_string(n) + " threads " + std::to_string(threads));
      TriangleBvh many;
      many.build(part, threads);
      ASSERT_EQ(many.node_count(), one.node_count());
      for (std::int32_t k = 0; k < one.node_count(); ++k) {
        ASSERT_EQ(many.node_box(k).lo, one.node_box(k).lo) << "node " << k;
        ASSERT_EQ(many.node_box(k).hi, one.node_box(k).hi) << "node " << k;
        ASSERT_EQ(many.node_min_id(k), one.node_min_id(k)) << "node " << k;
      }
      std::vector<Index> met_one, met_many;
      const AABB& q = part[n / 2];
      one.query(q, [] { return 0.05; }, [&](Index t, double) { met_one.push_back(t); });
      many.query(q, [] { return 0.05; }, [&](Index t, double) { met_many.push_back(t); });
      EXPECT_EQ(met_many, met_one);
    }
  }
}

/// The documented build, written plainly: node `slot` holds `ids`; above kLeafSize (4) they
/// split at the median (std::nth_element) along the longest side of their centres' box, by
/// centre coordinate then id, the children at `next` and next + 1, the left's descendants
/// after them, then the right's. Records each node's triangles, sorted.
std::int32_t twin_subtree_nodes(size_t n) { return n <= 4 ? 1 : 1 + twin_subtree_nodes(n / 2) + twin_subtree_nodes(n - n / 2); }
void twin_build(std::int32_t slot, std::vector<Index> ids, std::int32_t next, const std::vector<AABB>& boxes,
                std::vector<std::vector<Index>>& sets) {
  std::vector<Index> sorted = ids;
  std::sort(sorted.begin(), sorted.end());
  sets[static_cast<size_t>(slot)] = sorted;
  if (ids.size() <= 4) return;
  AABB cb;
  for (Index t : ids) cb.extend(boxes[static_cast<size_t>(t)].center());
  const Vec3 ext = cb.hi - cb.lo;
  int axis = 0;
  if (ext.y() > ext[axis]) axis = 1;
  if (ext.z() > ext[axis]) axis = 2;
  const size_t mid = ids.size() / 2;
  std::nth_element(ids.begin(), ids.begin() + static_cast<std::ptrdiff_t>(mid), ids.end(), [&](Index a, Index b) {
    const double ca = boxes[static_cast<size_t>(a)].center()[axis], cb2 = boxes[static_cast<size_t>(b)].center()[axis];
    return ca < cb2 || (ca == cb2 && a < b);
  });
  const std::vector<Index> left(ids.begin(), ids.begin() + static_cast<std::ptrdiff_t>(mid));
  const std::vector<Index> right(ids.begin() + static_cast<std::ptrdiff_t>(mid), ids.end());
  twin_build(next, left, next + 2, boxes, sets);
  twin_build(next + 1, right, next + 2 + twin_subtree_nodes(mid) - 1, boxes, sets);
}

TEST(TriangleBvh, BuildSplitsAtTheMedianAsDocumented) {
  // Every node holds the triangles the plain median-split build (twin_build) puts there, and
  // its box is the union of theirs: on a blob's boxes, and on point boxes on a coarse lattice
  // (many equal centre coordinates, where the id decides; -0 and +0 among them, which are
  // equal), with one thread and several.
  const Frame frame = make_random_frame(3, 1, 1.0, 2);
  const std::vector<AABB> blob = FrameBoxes::compute(frame, 1).triangles[0];
  std::vector<AABB> lattice;
  Rng rng(21);
  const double values[] = {-1.0, -0.0, 0.0, 1.0, 2.0};
  for (int k = 0; k < 777; ++k) {
    Vec3 p;
    for (int d = 0; d < 3; ++d) p[d] = values[rng.integer(0, 4)] * (d + 1);
    lattice.push_back({p, p});
  }
  for (const std::vector<AABB>* boxes : {&blob, static_cast<const std::vector<AABB>*>(&lattice)}) {
    for (size_t n : {boxes->size(), size_t{9}, size_t{5}, size_t{4}}) {
      const std::vector<AABB> part(boxes->begin(), boxes->begin() + static_cast<std::ptrdiff_t>(n));
      std::vector<std::vector<Index>> want(static_cast<size_t>(twin_subtree_nodes(n)));
      std::vector<Index> ids(n);
      std::iota(ids.begin(), ids.end(), 0);
      twin_build(0, ids, 1, part, want);
      for (int threads : {1, 3}) {
        SCOPED_TRACE("n " + std::to_string(n) + " threads " + std::to_string(threads));
        TriangleBvh bvh;
        bvh.build(part, threads);
        ASSERT_EQ(static_cast<size_t>(bvh.node_count()), want.size());
        const AABB everything{Vec3::Constant(-kInfinity), Vec3::Constant(kInfinity)};
        for (std::int32_t k = 0; k < bvh.node_count(); ++k) {
          std::vector<Index> got;
          AABB box;
          bvh.query_overlaps(everything, [](std::int32_t) { return false; }, [&](Index t) {
            got.push_back(t);
            box.extend(part[static_cast<size_t>(t)]);
          }, k);
          std::sort(got.begin(), got.end());
          ASSERT_EQ(got, want[static_cast<size_t>(k)]) << "node " << k;
          ASSERT_EQ(bvh.node_box(k).lo, box.lo) << "node " << k;
          ASSERT_EQ(bvh.node_box(k).hi, box.hi) << "node " << k;
        }
      }
    }
  }
}

TEST(TriangleBvh, SelfOverlapsVisitEveryOverlappingPairOnce) {
  // CCD's search within one object: descending the hierarchy against itself must visit every
  // unordered pair of distinct triangles whose boxes overlap, once, and nothing else; from the
  // root or from the node pairs of self_overlap_pairs() alike. With a skip that passes over
  // the node pairs all of whose ids are at least K (by node_min_id()), every pair with an id
  // below K must still be visited, and some pairs of larger ids are not.
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const Frame frame = make_random_frame(seed, 2, 1.0, 2);
    const FrameBoxes boxes = FrameBoxes::compute(frame, 1);
    for (const auto& mine : boxes.triangles) {
      TriangleBvh bvh;
      bvh.build(mine);
      const auto n = static_cast<Index>(mine.size());
      using PairSet = std::multiset<std::pair<Index, Index>>;
      auto record = [](PairSet& set) {
        return [&set](Index f, Index g) { set.insert({std::min(f, g), std::max(f, g)}); };
      };
      auto none = [](std::int32_t, std::int32_t) { return false; };
      PairSet expect;
      for (Index f = 0; f < n; ++f)
        for (Index g = f + 1; g < n; ++g)
          if (boxes_overlap(mine[static_cast<size_t>(f)], mine[static_cast<size_t>(g)])) expect.insert({f, g});
      PairSet from_root, from_pairs;
      bvh.self_overlaps({0, 0}, none, record(from_root));
      const auto starts = bvh.self_overlap_pairs(16, none);
      for (const auto& sp : starts) bvh.self_overlaps(sp, none, record(from_pairs));
      ASSERT_EQ(from_root, expect) << "seed " << seed;
      ASSERT_EQ(from_pairs, expect) << "seed " << seed;
      EXPECT_GT(starts.size(), 4u);
      const Index k = n / 3;
      auto large = [&](std::int32_t a, std::int32_t b) { return bvh.node_min_id(a) >= k && bvh.node_min_id(b) >= k; };
      PairSet skipped_root, skipped_pairs;
      bvh.self_overlaps({0, 0}, large, record(skipped_root));
      for (const auto& sp : bvh.self_overlap_pairs(16, large)) bvh.self_overlaps(sp, large, record(skipped_pairs));
      EXPECT_EQ(skipped_root, skipped_pairs) << "seed " << seed;
      PairSet small_expect, small_got;
      for (const auto& p : expect)
        if (p.first < k) small_expect.insert(p);
      for (const auto& p : skipped_root) {
        EXPECT_EQ(expect.count(p), 1u) << p.first << " " << p.second;
        if (p.first < k) small_got.insert(p);
      }
      EXPECT_EQ(small_got, small_expect) << "seed " << seed;
      EXPECT_LT(skipped_root.size(), expect.size()) << "seed " << seed;
    }
  }
}

TEST(TriangleBvhPairSearch, VisitsExactlyThePairsWithinTheBound) {
  // A random frame's objects as hierarchies, every ordered pair of them, and a fixed bound:
  // the search must visit every (pair, triangle of a, triangle of b) whose boxes are within the
  // bound, once, and nothing else, also when pairs are added between runs (in lower-bound
  // order, after a run up to that lower bound). Then with triangles of a dropped: through
  // keep_triangle by id and value, and through keep_node by node_min_id() and node_min(),
  // which may drop a subtree only when every triangle in it is dropped too.
  const Frame frame = make_random_frame(7, 5, 1.2, 1);
  const FrameBoxes boxes = FrameBoxes::compute(frame, 1);
  const size_t n = frame.objects.size();
  std::vector<TriangleBvh> bvhs(n);
  for (size_t i = 0; i < n; ++i) bvhs[i].build(boxes.triangles[i]);
  std::vector<std::pair<size_t, size_t>> pairs;
  for (size_t a = 0; a < n; ++a)
    for (size_t b = 0; b < n; ++b)
      if (a != b) pairs.emplace_back(a, b);
  auto root_d2 = [&](const std::pair<size_t, size_t>& p) {
    return box_distance_squared(boxes.objects[p.first], boxes.objects[p.second]);
  };
  std::sort(pairs.begin(), pairs.end(), [&](const auto& x, const auto& y) { return root_d2(x) < root_d2(y); });
  // Per object, a value per triangle (as D_l), and per node the smallest of them.
  Rng rng(3);
  std::vector<std::vector<double>> value(n);
  std::vector<std::vector<double>> node_value(n);
  for (size_t i = 0; i < n; ++i) {
    for (size_t t = 0; t < boxes.triangles[i].size(); ++t) value[i].push_back(rng.uniform(0, 1));
    node_value[i] = bvhs[i].node_min(value[i]);
  }
  // Per object, the projections onto the diagonals of its triangles and nodes: with them,
  // "within the bound" is of the boxes' squared distance raised to gap^2 / 3.
  std::vector<HierarchyDiagonals> diag(n);
  for (size_t i = 0; i < n; ++i) {
    diag[i].triangles = triangle_diagonals(frame.objects[i]);
    diag[i].nodes = node_diagonals(bvhs[i], diag[i].triangles);
  }
  auto pair_d2 = [&](size_t a, Index ta, size_t b, Index tb, bool diagonals) {
    const double d2 = box_distance_squared(boxes.triangles[a][static_cast<size_t>(ta)], boxes.triangles[b][static_cast<size_t>(tb)]);
    const double gap = diagonals ? diagonal_gap(diag[a].triangles[static_cast<size_t>(ta)], diag[b].triangles[static_cast<size_t>(tb)]) : 0;
    return std::max(d2, gap * gap / 3);
  };
  using Key = std::tuple<size_t, Index, Index>;
  size_t visited_max = 0, fewer = 0;
  std::array<size_t, 3> boxes_only{};  // pairs visited without the diagonals, per kind of drop
  for (double bound : {0.0, 0.05, 0.3, 10.0})
    for (int drop = 0; drop < 6; ++drop) {
      // drop 3-5: as 0-2, with the diagonals.
      const bool diagonals = drop >= 3;
      SCOPED_TRACE("bound " + std::to_string(bound) + " drop " + std::to_string(drop));
      // drop 1: triangles of a with id above a limit of the pair; drop 2: those with value
      // above one.
      auto id_limit = [](size_t p) { return static_cast<Index>(p * 7 % 60); };
      auto value_limit = [](size_t p) { return 0.1 + 0.8 * static_cast<double>(p % 5) / 4; };
      auto kept = [&](size_t p, Index t) {
        const size_t a = pairs[p].first;
        return drop % 3 == 0 || (drop % 3 == 1 ? t <= id_limit(p) : value[a][static_cast<size_t>(t)] <= value_limit(p));
      };
      std::multiset<Key> expected;
      for (size_t p = 0; p < pairs.size(); ++p) {
        const auto [a, b] = pairs[p];
        for (Index ta = 0; ta < static_cast<Index>(boxes.triangles[a].size()); ++ta)
          for (Index tb = 0; tb < static_cast<Index>(boxes.triangles[b].size()); ++tb)
            if (kept(p, ta) && pair_d2(a, ta, b, tb, diagonals) <= bound * bound) expected.insert({p, ta, tb});
      }
      TriangleBvh::PairSearch search;
      std::multiset<Key> got;
      auto bnd = [&] { return bound; };
      auto keep_node = [&](size_t p, std::int32_t node) {
        const size_t a = pairs[p].first;
        return drop % 3 == 0 || (drop % 3 == 1 ? bvhs[a].node_min_id(node) <= id_limit(p)
                                               : node_value[a][static_cast<size_t>(node)] <= value_limit(p));
      };
      auto keep_triangle = [&](size_t p, Index t) { return kept(p, t); };
      auto visit = [&](size_t p, Index ta, Index tb, double d2) {
        const auto [a, b] = pairs[p];
        EXPECT_EQ(d2, pair_d2(a, ta, b, tb, diagonals));
        got.insert({p, ta, tb});
      };
      for (const auto& pr : pairs) {
        search.run(bnd, keep_node, keep_triangle, visit, root_d2(pr));
        if (diagonals)
          search.add(bvhs[pr.first], bvhs[pr.second], bound, &diag[pr.first], &diag[pr.second]);
        else
          search.add(bvhs[pr.first], bvhs[pr.second], bound);
      }
      search.run(bnd, keep_node, keep_triangle, visit);
      EXPECT_EQ(got, expected);
      visited_max = std::max(visited_max, got.size());
      if (!diagonals) boxes_only[drop] = got.size();
      else fewer += got.size() < boxes_only[drop - 3];
    }
  EXPECT_GT(visited_max, 1000u);  // the frame's objects do come within the bounds
  EXPECT_GE(fewer, 6u);           // and the diagonals pass some of their pairs over
}

TEST(InterDistance, SheetsAslantAreCulledAlongTheDiagonals) {
  // Two sheets with normal (1, 1, 1), 1 apart along it, and beside each a small triangle 0.1
  // from its middle on its far side: each sheet's answer is its small triangle. Boxes across
  // the sheets overlap (hundreds of triangle pairs), but the gap along the diagonal (1, 1, 1)
  // bounds their distance by 1, so no pair across them is looked at.
  const int n = 10;
  const test::AslantFrame w;
  const Vec3 &u = w.u, &v = w.v, &normal = w.normal;
  Frame frame;
  const Vec3 middle = 0.5 * n * (u + v);
  for (int sheet = 0; sheet < 2; ++sheet)
    frame.objects.push_back(test::make_aslant_sheet(n, sheet * 1.0, "sheet" + std::to_string(sheet)));
  for (int sheet = 0; sheet < 2; ++sheet) {
    const Vec3 c = middle + (sheet == 0 ? -0.1 : 1.1) * normal;
    frame.objects.push_back(test::make_object({c, c + 0.3 * u, c + 0.3 * v}, {Face{0, 1, 2}}, "near" + std::to_string(sheet)));
  }
  const auto got = inter_object_distance(frame, {1, nullptr});
  test::expect_same_inter(got, inter_object_distance_brute_force(frame), "sheets aslant");
  ASSERT_EQ(got.per_object[0].nearest_object, 2);
  ASSERT_EQ(got.per_object[1].nearest_object, 3);
  std::uint64_t overlapping = 0;
  const FrameBoxes boxes = FrameBoxes::compute(frame, 1);
  for (const AABB& a : boxes.triangles[0])
    for (const AABB& b : boxes.triangles[1]) overlapping += boxes_overlap(a, b);
  EXPECT_GT(overlapping, 100u);
  // Looked at: the triangle pairs tested or culled by separation_lower_bound(), 24 in all
  // (without the diagonals, 804).
  const std::uint64_t looked_at = got.counters.exact_tests + got.counters.separation_culled;
  EXPECT_LT(looked_at, 100u) << overlapping << " pairs across the sheets have overlapping boxes";
}

TEST(ObjectBroadPhase, BoundsAndPnsAreConservative) {
  for (std::uint64_t seed = 20; seed < 30; ++seed) {
    const Frame frame = make_random_frame(seed, 12, 4.0, 1);
    const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
    const ObjectBroadPhase bp = object_broad_phase(frame, boxes, 2);
    const auto ref = inter_object_distance_brute_force(frame);
    for (size_t i = 0; i < frame.objects.size(); ++i) {
      // U_i bounds the true separation distance from above...
      EXPECT_GE(bp.upper_bound[i], ref.per_object[i].distance) << "seed " << seed << " object " << i;
      // ...and every object within U_i (in particular the nearest) is in PNS(i).
      for (size_t j = 0; j < frame.objects.size(); ++j) {
        if (j == i) continue;
        const double dij = object_distance(frame, i, j);
        if (dij <= bp.upper_bound[i]) {
          const auto& p = bp.pns[i];
          EXPECT_NE(std::find(p.begin(), p.end(), static_cast<Index>(j)), p.end())
              << "seed " << seed << ": object " << j << " at " << dij << " <= U=" << bp.upper_bound[i]
              << " missing from PNS(" << i << ")";
        }
      }
    }
  }
}

// Interpenetrating objects: where the nearest-corner walk of Stage I ends near the crossing
// of their surfaces, the triangles there meet (exact test), and U_i is 0, the objects'
// distance; objects apart keep a positive bound. The walk does not always end there (a
// heuristic: 8 of these 10 objects get 0; at least 5 must), and never gives a bound below the
// distance. Answers equal the brute force.
TEST(ObjectBroadPhase, InterpenetratingObjectsGetABoundOfZero) {
  std::size_t zero = 0;
  for (std::uint64_t seed = 1; seed <= 5; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Rng rng(seed);
    Frame frame;
    frame.objects.push_back(make_blob(rng, Vec3(0, 0, 0), 1.0, 2, 0.1, "a"));
    frame.objects.push_back(make_blob(rng, Vec3(1.3, 0.2 * static_cast<double>(seed), 0), 0.8, 2, 0.1, "b"));
    frame.objects.push_back(make_blob(rng, Vec3(6, 0, 0), 0.5, 1, 0.1, "apart"));
    const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
    const ObjectBroadPhase bp = object_broad_phase(frame, boxes, 2);
    const auto ref = inter_object_distance_brute_force(frame);
    ASSERT_EQ(ref.per_object[0].distance, 0.0);
    ASSERT_EQ(ref.per_object[1].distance, 0.0);
    for (size_t i = 0; i < 3; ++i) EXPECT_GE(bp.upper_bound[i], ref.per_object[i].distance);
    zero += (bp.upper_bound[0] == 0) + (bp.upper_bound[1] == 0);
    EXPECT_GT(bp.upper_bound[2], 0.0);
    test::expect_same_inter(inter_object_distance(frame, {2, nullptr}), ref, "seed " + std::to_string(seed));
  }
  std::printf("[          ] interpenetrating objects with U_i = 0: %zu of 10\n", zero);
  EXPECT_GE(zero, 5u);
}

// In a crowd, the candidates of U_i are often not the object i touches (many boxes lie at
// distance 0); Stage I also walks to a few objects whose boxes overlap i's and probes there.
// Random crowds of 40 blobs: the probe proves contact for most touching objects, never
// claims it for the others, and the answers equal the brute force.
TEST(ObjectBroadPhase, ContactIsFoundForMostTouchingObjectsOfACrowd) {
  std::size_t touching = 0, proven = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Frame frame = make_random_frame(seed + 60, 40, 4.0, 1);
    const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
    const ObjectBroadPhase bp = object_broad_phase(frame, boxes, 2);
    const auto ref = inter_object_distance_brute_force(frame);
    for (size_t i = 0; i < frame.objects.size(); ++i) {
      EXPECT_GE(bp.upper_bound[i], ref.per_object[i].distance);
      touching += ref.per_object[i].distance == 0;
      proven += bp.upper_bound[i] == 0;
    }
    test::expect_same_inter(inter_object_distance(frame, {2, nullptr}), ref, "seed " + std::to_string(seed));
  }
  std::printf("[          ] touching objects with U_i = 0: %zu of %zu\n", proven, touching);
  ASSERT_GT(touching, 40u);
  EXPECT_GE(10 * proven, 9 * touching);
}

// A crowd of small objects, where the axis rule alone picks far objects and the PNS search
// must not visit every object: the PNS is exactly the boxes within U_i (+ slack), sorted as
// documented; U_i is at most the farthest-corner distance to every other box; the answers
// equal brute force.
TEST(ObjectBroadPhase, CrowdOfSmallObjects) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    Rng rng(seed);
    Frame frame;
    const double side = 20;
    for (int i = 0; i < 300; ++i) {
      const Vec3 c = rng.vec3(0, side);
      frame.objects.push_back(make_soup(rng, c, 0.2, 0.5, 1 + i % 3, "o" + std::to_string(i)));
    }
    const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
    const ObjectBroadPhase bp = object_broad_phase(frame, boxes, 2);
    const auto ref = inter_object_distance_brute_force(frame);
    const double slack = rounding_slack(boxes.magnitude);
    double sum_u = 0;
    for (size_t i = 0; i < frame.objects.size(); ++i) {
      const std::string where = "seed " + std::to_string(seed) + " object " + std::to_string(i);
      const double u = bp.upper_bound[i];
      EXPECT_GE(u, ref.per_object[i].distance) << where;
      std::vector<std::pair<double, Index>> within;
      for (size_t j = 0; j < frame.objects.size(); ++j) {
        if (j == i) continue;
        EXPECT_LE(u, box_max_distance(boxes.objects[i], boxes.objects[j]) * (1 + 1e-12)) << where << " vs " << j;
        const double d2 = box_distance_squared(boxes.objects[i], boxes.objects[j]);
        if (d2 <= (u + slack) * (u + slack)) within.emplace_back(d2, static_cast<Index>(j));
      }
      std::sort(within.begin(), within.end());
      std::vector<Index> expected;
      for (const auto& w : within) expected.push_back(w.second);
      EXPECT_EQ(bp.pns[i], expected) << where;
      sum_u += u;
    }
    // The bounds are local (about 1.4 here; the axis rule alone gave about 5.5).
    EXPECT_LT(sum_u / static_cast<double>(frame.objects.size()), side / 10) << "seed " << seed;
    test::expect_same_inter(inter_object_distance(frame, {2}), ref, "crowd seed " + std::to_string(seed));
  }
}

// Long parallel sticks side by side (every x-interval overlaps every other, every box's
// farthest corner is a stick's length away): U_i is at most the distance to a neighbouring
// stick's surface, found by walking to the nearest box, so the PNS holds the neighbours and
// not most of the sticks (which made Stage I quadratic in their number); the answers equal
// brute force.
TEST(ObjectBroadPhase, LongParallelSticksKeepLocalBounds) {
  Frame frame;
  const int side = 12;
  for (int a = 0; a < side; ++a)
    for (int b = 0; b < side; ++b) {
      const double y = a + 0.01 * ((a * 7 + b * 3) % 5), z = b + 0.01 * ((a + b * 5) % 7);
      frame.objects.push_back(test::make_object({{0, y, z}, {1000, y + 0.1, z}, {1000, y + 0.05, z + 0.05}, {0, y + 0.1, z + 0.05}},
                                          {{0, 1, 2}, {0, 2, 3}}, "s" + std::to_string(a * side + b)));
    }
  const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
  const ObjectBroadPhase bp = object_broad_phase(frame, boxes, 2);
  const auto ref = inter_object_distance_brute_force(frame);
  for (size_t i = 0; i < frame.objects.size(); ++i) {
    EXPECT_GE(bp.upper_bound[i], ref.per_object[i].distance) << "stick " << i;
    EXPECT_LT(bp.upper_bound[i], 1.5) << "stick " << i;  // a neighbour is about 1 away
    EXPECT_LE(bp.pns[i].size(), 12u) << "stick " << i;
  }
  test::expect_same_inter(inter_object_distance(frame, {2}), ref, "sticks");
}

/// Nested shells around one centre, small blobs inside the outermost, and one shell off centre
/// that cuts through two others: boxes that contain each other, so every box distance is 0.
Frame nested_frame(std::uint64_t seed) {
  Rng rng(seed);
  Frame frame;
  const Vec3 c = rng.vec3(-1, 1);
  for (int k = 0; k < 6; ++k)
    frame.objects.push_back(make_blob(rng, c, 1.0 + 0.35 * k, 2, 0.03, "shell" + std::to_string(k)));
  for (int k = 0; k < 4; ++k) {
    const Vec3 at = c + rng.vec3(-1, 1).normalized() * 2.6;
    frame.objects.push_back(make_blob(rng, at, 0.1, 1, 0.2, "grain" + std::to_string(k)));
  }
  frame.objects.push_back(make_blob(rng, c + Vec3(0.5, 0, 0), 1.5, 2, 0.03, "off-centre"));
  return frame;
}

// enclosure_lower_bound() from all triangles: the objects' box centres, their farthest corner and
// nearest triangle (point_triangle_distance() on every one), combined as the header says.
double enclosure_twin(const Frame& frame, const FrameBoxes& boxes, size_t i, size_t j) {
  struct Shell {
    Vec3 c;
    double outer, inner;
  };
  auto shell = [&](size_t k) {
    const Object& o = frame.objects[k];
    const Vec3 c = boxes.objects[k].center();
    double outer2 = 0, inner2 = kInfinity;
    for (Index t = 0; t < o.num_triangles(); ++t) {
      for (const Vec3& v : o.triangle(t)) outer2 = std::max(outer2, (v - c).squaredNorm());
      inner2 = std::min(inner2, point_triangle_distance(c, o.triangle(t)).squared_distance);
    }
    return Shell{c, std::sqrt(outer2), std::sqrt(inner2)};
  };
  const Shell a = shell(i), b = shell(j);
  const double apart = (a.c - b.c).norm();
  const double lb = std::max(b.inner - apart - a.outer, a.inner - apart - b.outer);
  return std::max(0.0, lb - rounding_slack(std::max(boxes.magnitudes[i], boxes.magnitudes[j])));
}

// The enclosure bound (object_broad_phase.hpp) never exceeds the true distance between two
// objects, nested or not; and it separates nested shells whose boxes contain each other.
TEST(ObjectBroadPhase, EnclosureBoundIsALowerBound) {
  int nested_positive = 0;
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    for (const Frame& frame : {nested_frame(seed), make_random_frame(seed, 8, 1.0 + static_cast<double>(seed), 1)}) {
      const bool nested = frame.objects.size() == 11;
      const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
      for (size_t i = 0; i < frame.objects.size(); ++i)
        for (size_t j = 0; j < frame.objects.size(); ++j) {
          if (i == j) continue;
          const double dij = object_distance(frame, i, j);
          const double lb = enclosure_lower_bound(frame, boxes, static_cast<Index>(i), static_cast<Index>(j));
          EXPECT_LE(lb, dij) << "seed " << seed << " objects " << i << ", " << j;
          EXPECT_EQ(lb, enclosure_lower_bound(frame, boxes, static_cast<Index>(j), static_cast<Index>(i)));
          // Bitwise the bound from every triangle's point-triangle distance: the triangles the
          // search passes over (by box or plane) change nothing.
          EXPECT_EQ(lb, enclosure_twin(frame, boxes, i, j)) << "seed " << seed << " objects " << i << ", " << j;
          // The 6 concentric shells (30 ordered pairs per frame).
          nested_positive += nested && i < 6 && j < 6 && lb > 0;
        }
    }
  }
  EXPECT_GE(nested_positive, 2 * 24);  // most: coarse blobs have a thin hollow
}

// Nested shells and objects inside a closed surface: the answers equal brute force, and the
// search leaves out the objects that the enclosure bound puts beyond the answer (with box
// distances alone, every object's search went through every other object).
TEST(InterDistance, NestedShellsEqualBruteForce) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    const Frame frame = nested_frame(seed);
    const auto ref = inter_object_distance_brute_force(frame);
    const auto got = inter_object_distance(frame, {2});
    test::expect_same_inter(got, ref, "nested seed " + std::to_string(seed));
    // 29-31 object pairs searched (of 110); 57-59 with box distances alone.
    EXPECT_LE(got.counters.object_pns_pairs, 40u) << "seed " << seed;
  }
}

TEST(OverlappingBoxPairs, EqualsAllPairs) {
  // Integer boxes in a small range: many touch exactly (closed boxes count), some coincide;
  // every seventh id is left out of the query.
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    Rng rng(seed);
    const int n = rng.integer(0, 300);
    std::vector<AABB> boxes(static_cast<size_t>(n));
    std::vector<Index> ids;
    for (int i = 0; i < n; ++i) {
      for (int k = 0; k < 3; ++k) {
        const double lo = rng.integer(0, 30);
        boxes[static_cast<size_t>(i)].lo[k] = lo;
        boxes[static_cast<size_t>(i)].hi[k] = lo + rng.integer(0, 4);
      }
      if (i % 7 != 3) ids.push_back(i);
    }
    std::vector<std::pair<Index, Index>> expected;
    for (size_t a = 0; a < ids.size(); ++a)
      for (size_t b = a + 1; b < ids.size(); ++b)
        if (boxes_overlap(boxes[static_cast<size_t>(ids[a])], boxes[static_cast<size_t>(ids[b])]))
          expected.emplace_back(ids[a], ids[b]);
    for (int threads : {1, 3})
      EXPECT_EQ(overlapping_box_pairs(ObjectBoxTree::build(boxes, ids), boxes, threads), expected) << "seed " << seed << " threads " << threads;
  }
}

}  // namespace
}  // namespace vproxq
