// Intra-object (self) distance: Stage III (AABB-only and with Stage II's bounds) against the
// all-non-adjacent-pairs brute force, per triangle and bitwise.
#include "core/geometry/point_triangle.hpp"
#include "core/mesh/adjacency.hpp"
#include "core/query/intersecting_pairs.hpp"
#include "core/query/intra_distance.hpp"
#include "core/voronoi/self_stage2.hpp"
#include "support/random_scene.hpp"
#include "support/self_meshes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstddef>

namespace vproxq {
namespace {

using test::expect_same_intra;
using test::Rng;

Frame frame_of(std::vector<Object> objects) {
  Frame f;
  f.objects = std::move(objects);
  return f;
}

/// Scenes of every kind the self query must handle, by seed.
std::vector<std::pair<std::string, Frame>> scenes() {
  std::vector<std::pair<std::string, Frame>> out;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    Rng rng(seed);
    // Blobs with strong jitter (creases, some self-intersections), several objects per frame.
    Frame blobs;
    for (int i = 0; i < 3; ++i)
      blobs.objects.push_back(test::make_blob(rng, Vec3(3.0 * i, 0, 0), 1.0, 2, 0.5, "blob"));
    out.emplace_back("blobs seed " + std::to_string(seed), std::move(blobs));
    // A soup: no shared vertices, every pair non-adjacent, many intersections.
    out.emplace_back("soup seed " + std::to_string(seed),
                     frame_of({test::make_soup(rng, Vec3::Zero(), 0.5, 0.3, 60, "soup")}));
    // Folded sheets, the gap from well below to above the cell size.
    const double gap = 0.02 * std::pow(4.0, static_cast<double>(seed - 1));
    out.emplace_back("folded sheet gap " + std::to_string(gap),
                     frame_of({test::make_folded_sheet(rng, 16, 6, 0.1, gap, 0.1)}));
    out.emplace_back("irregular seed " + std::to_string(seed),
                     frame_of({test::make_irregular_mesh(rng)}));
  }
  // A tetrahedron (no triangle has an answer) beside two tetrahedra in one object (every
  // triangle's answer is in the other one).
  out.emplace_back("tetrahedra", frame_of({test::make_tetrahedra(1, 0, "one"), test::make_tetrahedra(2, 1.5, "two")}));
  return out;
}

/// Every candidate pair is culled by Stage II or by the separation bound, reused from the
/// other triangle's search, or evaluated.
void expect_candidates_accounted(const DistanceCounters& c, const std::string& name) {
  EXPECT_EQ(c.intra_candidates, c.intra_voronoi_culled + c.intra_separation_culled +
                                    c.intra_reused + c.intra_exact_tests)
      << name;
}

/// The brute force's intersecting pairs within objects (exact intersection test on every pair
/// sharing no vertex), of the objects `keep` accepts.
template <typename Keep>
std::vector<IntersectingPair> intra_intersecting_reference(const Frame& frame, const Keep& keep) {
  std::vector<IntersectingPair> out;
  for (const IntersectingPair& p : intersecting_pairs_brute_force(frame, true).pairs)
    if (p.object_a == p.object_b && keep(static_cast<size_t>(p.object_a))) out.push_back(p);
  return out;
}
std::vector<IntersectingPair> intra_intersecting_reference(const Frame& frame) {
  return intra_intersecting_reference(frame, [](size_t) { return true; });
}

/// The search's intersecting pairs are the brute force's.
void expect_intersecting_pairs(const IntraDistanceOutput& got, const std::vector<IntersectingPair>& ref,
                               const std::string& name) {
  EXPECT_EQ(got.intersecting, ref) << name;
}

TEST(IntraDistance, EqualsBruteForceOnAllScenesAndThreadCounts) {
  std::uint64_t reused = 0, separated = 0;
  size_t intersecting = 0;
  for (const auto& [name, frame] : scenes()) {
    const auto ref = intra_object_distance_brute_force(frame);
    const auto ref_pairs = intra_intersecting_reference(frame);
    intersecting += ref_pairs.size();
    for (int threads : {1, 3}) {
      const auto got = intra_object_distance(frame, {threads});
      expect_same_intra(got, ref, name + ", threads " + std::to_string(threads));
      expect_intersecting_pairs(got, ref_pairs, name + ", threads " + std::to_string(threads));
      EXPECT_LE(got.counters.intra_exact_tests, ref.counters.intra_exact_tests) << name;
      expect_candidates_accounted(got.counters, name);
      reused += got.counters.intra_reused;
      separated += got.counters.intra_separation_culled;
    }
  }
  // Pairs wanted by both triangles are evaluated once for both; pairs whose boxes are within
  // the bound but whose triangles are not are skipped untested.
  EXPECT_GT(reused, 0u);
  EXPECT_GT(separated, 0u);
  // The soups and jittered blobs intersect themselves, or the pair lists prove little.
  EXPECT_GT(intersecting, 100u);
}

// Large soups, searched by 3 threads in units of at most 256 triangles (node pairs of the
// descent): each intersecting pair is listed once, whichever unit met it.
TEST(IntraDistance, IntersectingPairsOfLargeObjectsOnManyThreadsAreListedOnce) {
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    Rng rng(seed);
    const Frame frame = frame_of({test::make_soup(rng, Vec3::Zero(), 1.0, 0.25, 800, "soup"),
                                  test::make_soup(rng, Vec3(0.5, 0, 0), 1.0, 0.25, 500, "soup")});
    const auto ref = intra_intersecting_reference(frame);
    EXPECT_GT(ref.size(), 500u);
    for (int round = 0; round < 3; ++round)
      expect_intersecting_pairs(intra_object_distance(frame, {3}), ref, "seed " + std::to_string(seed));
  }
}

// Objects left out (a caller's cached static objects) are not searched: their pairs are missing
// from the list, and the intersecting pairs search them itself (given the same mask). Together the lists equal the
// brute force's, inter-object pairs included.
TEST(IntraDistance, IntersectingPairsOfObjectsLeftOutComeFromTheirOwnSearch) {
  size_t left_out_pairs = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    Rng rng(seed);
    Frame frame;
    for (int i = 0; i < 4; ++i)
      frame.objects.push_back(i % 2 == 0 ? test::make_soup(rng, Vec3(0.4 * i, 0, 0), 0.5, 0.3, 40, "soup")
                                         : test::make_blob(rng, Vec3(0.4 * i, 0, 0), 0.6, 2, 0.5, "blob"));
    const std::vector<std::uint8_t> skip = {0, 0, 1, 0};
    const auto all = intersecting_pairs_brute_force(frame, true).pairs;
    const auto kept = intra_intersecting_reference(frame, [&](size_t i) { return skip[i] == 0; });
    left_out_pairs += intra_intersecting_reference(frame, [&](size_t i) { return skip[i] != 0; }).size();
    for (int threads : {1, 3}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + ", threads " + std::to_string(threads));
      const auto got = intra_object_distance(frame, {threads, nullptr, &skip});
      EXPECT_EQ(got.intersecting, kept);
      IntersectingPairsOptions opts{threads, nullptr, true};
      opts.intra_pairs = &got.intersecting;
      opts.intra_skip = &skip;
      const auto merged = intersecting_pairs(frame, opts);
      EXPECT_EQ(merged.pairs, all);
      // The claimed objects are not searched again: fewer tests than a search of all.
      EXPECT_LT(merged.exact_tests, intersecting_pairs(frame, {threads, nullptr, true}).exact_tests);
    }
  }
  EXPECT_GT(left_out_pairs, 20u);
}

TEST(IntraDistance, SortedScanReferenceEqualsBruteForce) {
  for (const auto& [name, frame] : scenes())
    expect_same_intra(intra_object_distance_sorted_scan(frame, 2),
                      intra_object_distance_brute_force(frame), name + ", sorted scan");
}

/// The 2-ring bound by its definition: the smallest distance between a vertex of t and a
/// vertex of a triangle of Adjacency::ring2(t), widened as ring2_upper_bounds() widens it.
double ring2_bound_by_definition(const Object& o, Index t) {
  const auto& faces = o.topology->faces;
  double best2 = kInfinity;
  for (Index g : adjacency(*o.topology).ring2(t))
    for (Index a : faces[static_cast<size_t>(t)])
      for (Index b : faces[static_cast<size_t>(g)])
        best2 = std::min(best2, (o.positions[static_cast<size_t>(a)] - o.positions[static_cast<size_t>(b)]).squaredNorm());
  return std::sqrt(best2) * (1 + 1e-12);
}

TEST(IntraDistance, Ring2BoundIsTheWholeRingsAndAnUpperBound) {
  // No vertex of these meshes is used by more than 64 triangles: the bound is the whole
  // 2-ring's.
  for (const auto& [name, frame] : scenes()) {
    const auto ref = intra_object_distance_brute_force(frame);
    const auto bound = ring2_upper_bounds(frame, 2);
    for (size_t i = 0; i < frame.objects.size(); ++i)
      for (Index t = 0; t < frame.objects[i].num_triangles(); ++t) {
        const double u = bound[i][static_cast<size_t>(t)];
        EXPECT_GE(u, ref.per_object[i].per_triangle[static_cast<size_t>(t)].distance) << name;
        EXPECT_EQ(u, ring2_bound_by_definition(frame.objects[i], t)) << name << " triangle " << t;
      }
  }
}

TEST(IntraDistance, Ring2BoundSkipsHubsAndStaysAnUpperBound) {
  // A closed cylinder whose caps are fans of n triangles around a hub vertex (valence n): the
  // walk skips the hubs, so cap triangles get their bound from the rim's side triangles.
  const int n = 200;
  std::vector<Vec3> p;
  std::vector<Face> faces;
  for (int z = 0; z < 2; ++z)
    for (int k = 0; k < n; ++k) {
      const double a = 2 * M_PI * k / n;
      p.emplace_back(std::cos(a), std::sin(a), 0.3 * z);
    }
  p.emplace_back(0, 0, 0);
  p.emplace_back(0, 0, 0.3);
  const Index hub0 = 2 * n, hub1 = 2 * n + 1;
  for (Index k = 0; k < n; ++k) {
    const Index j = (k + 1) % n;
    faces.push_back({hub0, j, k});
    faces.push_back({hub1, n + k, n + j});
    faces.push_back({k, j, n + j});
    faces.push_back({k, n + j, n + k});
  }
  const Frame frame = frame_of({test::make_object(p, faces, "cylinder")});
  const Object& o = frame.objects[0];
  const auto ref = intra_object_distance_brute_force(frame);
  const auto bound = ring2_upper_bounds(frame, 2);
  for (Index t = 0; t < o.num_triangles(); ++t) {
    const double u = bound[0][static_cast<size_t>(t)];
    const double whole = ring2_bound_by_definition(o, t);
    EXPECT_GE(u, ref.per_object[0].per_triangle[static_cast<size_t>(t)].distance) << t;
    EXPECT_GE(u, whole) << t;
    // Here the nearest vertices of every triangle's 2-ring are rim or side vertices next to
    // it (2 sin(pi / n) away), which the walk reaches without a hub: the bound is the whole
    // 2-ring's all the same.
    EXPECT_EQ(u, whole) << t;
    EXPECT_LT(u, 0.1) << t;
  }
  expect_same_intra(intra_object_distance(frame, {2}), ref, "cylinder with fan caps");
}

TEST(IntraDistance, AFarAwayObjectDoesNotWidenTheOthersSearch) {
  // The rounding slack of an object's search comes from its own coordinates: a blob parked at
  // 1e12 (whose slack is 100 units) must not turn the sheet's search into all pairs.
  Rng rng(5);
  const Object sheet = test::make_folded_sheet(rng, 16, 6, 0.1, 0.05, 0.1);
  const Frame alone = frame_of({sheet});
  const Frame with_far = frame_of({sheet, test::make_blob(rng, Vec3::Constant(1e12), 1.0, 1, 0.2, "far")});
  const auto ref = intra_object_distance_brute_force(with_far);
  const auto got = intra_object_distance(with_far, {2});
  expect_same_intra(got, ref, "sheet and a far blob");
  const auto sheet_only = intra_object_distance(alone, {1});
  const auto both = intra_object_distance(with_far, {1});
  const auto blob_only = intra_object_distance(frame_of({with_far.objects[1]}), {1});
  EXPECT_EQ(both.counters.intra_candidates, sheet_only.counters.intra_candidates + blob_only.counters.intra_candidates);
}

TEST(IntraDistance, SheetsAslantAreCulledAlongTheDiagonals) {
  // One object of two flat sheets with normal (1, 1, 1), 1 apart along it (triangles 1 wide):
  // boxes across the sheets overlap (390 pairs of triangles, and their subtrees' throughout),
  // but the gap along the diagonal (1, 1, 1) bounds their distance, so few pairs across them
  // become candidates: 52 (without the diagonals, 5,628; and 7,892 in all against 1,740).
  const int n = 10;
  std::vector<Vec3> p;
  std::vector<Face> faces;
  for (int sheet = 0; sheet < 2; ++sheet) {
    const Object o = test::make_aslant_sheet(n, sheet * 1.0, "sheet");
    const Index base = static_cast<Index>(p.size());
    p.insert(p.end(), o.positions.begin(), o.positions.end());
    for (const Face& f : o.topology->faces) faces.push_back({f[0] + base, f[1] + base, f[2] + base});
  }
  const Frame both = frame_of({test::make_object(p, faces, "two sheets")});
  const auto got = intra_object_distance(both, {1});
  expect_same_intra(got, intra_object_distance_brute_force(both), "two sheets aslant");
  // Pairs across the sheets whose triangle boxes overlap: what boxes alone would not cull.
  const size_t half = faces.size() / 2;
  auto box = [&](size_t t) {
    AABB b;
    for (const Vec3& x : both.objects[0].triangle(static_cast<Index>(t))) b.extend(x);
    return b;
  };
  std::uint64_t overlapping = 0;
  for (size_t f = 0; f < half; ++f)
    for (size_t g = half; g < faces.size(); ++g) overlapping += boxes_overlap(box(f), box(g));
  EXPECT_GT(overlapping, 100u);
  std::uint64_t alone = 0;
  for (int sheet = 0; sheet < 2; ++sheet) {
    std::vector<Face> f(faces.begin() + sheet * static_cast<std::ptrdiff_t>(half), faces.begin() + (sheet + 1) * static_cast<std::ptrdiff_t>(half));
    alone += intra_object_distance(frame_of({test::make_object(p, f, "sheet")}), {1}).counters.intra_candidates;
  }
  ASSERT_GE(got.counters.intra_candidates, alone);
  EXPECT_LT(got.counters.intra_candidates - alone, overlapping) << overlapping << " pairs across the sheets have overlapping boxes";
}

TEST(IntraDistance, IrregularMeshExclusionsAreByVertexSharing) {
  Rng rng(7);
  const Frame frame = frame_of({test::make_irregular_mesh(rng)});
  const Object& o = frame.objects[0];
  const auto got = intra_object_distance(frame, {2});
  const auto& table = got.per_object[0].per_triangle;
  const auto& faces = o.topology->faces;
  bool some_zero = false;
  for (size_t t = 0; t < table.size(); ++t) {
    if (table[t].nearest == kNoIndex) {
      // Only when every other triangle shares a vertex with t.
      for (size_t g = 0; g < faces.size(); ++g)
        if (g != t) {
          EXPECT_TRUE(Adjacency::share_vertex(faces[t], faces[g])) << t << " " << g;
        }
      continue;
    }
    EXPECT_FALSE(Adjacency::share_vertex(faces[t], faces[static_cast<size_t>(table[t].nearest)]));
    some_zero = some_zero || table[t].distance == 0;
  }
  EXPECT_TRUE(some_zero);  // the crossing triangle intersects the sheet: reported as 0
  EXPECT_EQ(got.per_object[0].distance, 0.0);
}

TEST(IntraDistance, ObjectsWithoutNonAdjacentPairs) {
  // One triangle; two triangles sharing an edge; a fan around one vertex: no pair qualifies.
  const Frame frame = frame_of(
      {test::make_object({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}, {{0, 1, 2}}, "one"),
       test::make_object({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}}, {{0, 1, 2}, {1, 3, 2}}, "two"),
       test::make_object({{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {-1, 0, 0}, {0, -1, 0}},
                         {{0, 1, 2}, {0, 2, 3}, {0, 3, 4}, {0, 4, 1}}, "fan"),
       test::make_object({}, {}, "empty")});
  const auto got = intra_object_distance(frame, {2});
  const auto ref = intra_object_distance_brute_force(frame);
  expect_same_intra(got, ref, "no pairs");
  for (const auto& o : got.per_object) {
    EXPECT_FALSE(o.has_pair());
    EXPECT_EQ(o.distance, kInfinity);
    for (const auto& t : o.per_triangle) EXPECT_EQ(t.nearest, kNoIndex);
  }
}

// Lemma 2 for the self query: D_l(f) <= SD(f) <= D_u(f) for every triangle, at coarse and fine
// grids; and Stage III with these bounds still equals the brute force.
TEST(IntraStage2, CpuBoundsHoldAndResultsEqualBruteForce) {
  auto backend = make_cpu_self_voronoi_backend(2);
  for (const auto& [name, frame] : scenes()) {
    const auto ref = intra_object_distance_brute_force(frame);
    const auto ref_pairs = intra_intersecting_reference(frame);
    const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
    const auto ring2 = ring2_upper_bounds(frame, 2);
    for (int grid : {8, 24, 64}) {
      SCOPED_TRACE(name + ", grid " + std::to_string(grid));
      const SelfVoronoiBounds vb = compute_self_voronoi_bounds(frame, boxes, ring2, *backend, grid, 2);
      EXPECT_GT(vb.delta, 0.0);
      for (size_t i = 0; i < frame.objects.size(); ++i)
        for (size_t t = 0; t < ref.per_object[i].per_triangle.size(); ++t) {
          const double sd = ref.per_object[i].per_triangle[t].distance;
          ASSERT_LE(vb.triangle_lower[i][t], sd) << "object " << i << " triangle " << t;
          ASSERT_GE(vb.triangle_upper[i][t], sd) << "object " << i << " triangle " << t;
          ASSERT_LE(vb.triangle_upper[i][t], ring2[i][t]);
        }
      for (int threads : {1, 3}) {
        IntraDistanceOptions opts{threads, &vb};
        const auto got = intra_object_distance(frame, boxes, ring2, opts);
        expect_same_intra(got, ref, "voronoi cpu, threads " + std::to_string(threads));
        expect_intersecting_pairs(got, ref_pairs, "voronoi cpu, threads " + std::to_string(threads));
        expect_candidates_accounted(got.counters, name);
      }
    }
  }
}

/// Passes the input and output of the CPU self backend through, keeping both.
class Recorder final : public SelfVoronoiBackend {
 public:
  std::string name() const override { return "cpu"; }
  std::string device() const override { return ""; }
  double distance_error_bound(double extent) const override { return cpu->distance_error_bound(extent); }
  SelfDvdOutput compute(const SelfDvdInput& in) override {
    input = in;
    output = cpu->compute(in);
    return output;
  }
  std::unique_ptr<SelfVoronoiBackend> cpu = make_cpu_self_voronoi_backend(3);
  SelfDvdInput input;
  SelfDvdOutput output;
};

/// The frame-wide numbers (objects in order) of the backend input's triangles. The input holds
/// only the triangles the backend needs, in frame order, each with its object and its
/// object's vertex ids; so each is the next face of its object with those vertex ids (a
/// duplicate face is identical to its twin in everything Stage II looks at).
std::vector<size_t> frame_triangles_of(const Frame& frame, const SelfDvdInput& in) {
  std::vector<size_t> base(frame.objects.size() + 1, 0), next(frame.objects.size(), 0), out;
  for (size_t i = 0; i < frame.objects.size(); ++i) base[i + 1] = base[i] + static_cast<size_t>(frame.objects[i].num_triangles());
  for (size_t t = 0; t < in.dvd.tri_site.size(); ++t) {
    const auto site = static_cast<size_t>(in.dvd.tri_site[t]);
    const std::int32_t* v = &in.tri_vertices[3 * t];
    const auto& faces = frame.objects[site].topology->faces;
    size_t& f = next[site];
    while (f < faces.size() && !(faces[f][0] == v[0] && faces[f][1] == v[1] && faces[f][2] == v[2])) ++f;
    EXPECT_LT(f, faces.size()) << "input triangle " << t << " is no later face of object " << site;
    out.push_back(base[site] + f++);
  }
  return out;
}

/// Runs the self Stage II through a Recorder on every scene at grids 8, 24 and 64, and calls
/// check(frame, boxes, ring2, bounds, recorder) on each run.
template <typename Check>
void for_each_recorded_run(const Check& check) {
  for (const auto& [name, frame] : scenes()) {
    const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
    const auto ring2 = ring2_upper_bounds(frame, 2);
    for (int grid : {8, 24, 64}) {
      SCOPED_TRACE(name + ", grid " + std::to_string(grid));
      Recorder rec;
      const SelfVoronoiBounds vb = compute_self_voronoi_bounds(frame, boxes, ring2, rec, grid, 2);
      check(frame, boxes, ring2, vb, rec);
    }
  }
}

// The default self grid: sqrt(n) cells for one surface spanning the scene, but no cell below
// 0.7 of the median triangle, so a crowd of small objects is not sampled at cells far below its
// triangles (27.7 samples per triangle for 2,000 blobs before); clamped to [32, 512].
// Stage III with the tightest bounds Stage II may give, D_l(g) = D_u(g) = SD(g) (from the brute
// force), or D_l(g) anywhere in [SD(g) / 4, SD(g)] with D_u left to the 2-ring bound: the
// search drops many candidates by D_l, here and through a node's smallest D_l, and must still
// meet every triangle's nearest pair.
TEST(IntraStage2, TightBoundsStillGiveTheBruteForce) {
  std::uint64_t culled = 0;
  for (const auto& [name, frame] : scenes()) {
    const auto ref = intra_object_distance_brute_force(frame);
    const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
    const auto ring2 = ring2_upper_bounds(frame, 2);
    for (const bool exact : {true, false}) {
      SCOPED_TRACE(name + (exact ? ", D_l = D_u = SD" : ", D_l in [SD / 4, SD]"));
      Rng rng(17);
      SelfVoronoiBounds vb;
      vb.triangle_upper.resize(frame.objects.size());
      vb.triangle_lower.resize(frame.objects.size());
      for (size_t i = 0; i < frame.objects.size(); ++i)
        for (size_t t = 0; t < ref.per_object[i].per_triangle.size(); ++t) {
          const double sd = ref.per_object[i].per_triangle[t].distance;  // infinite: no pair
          vb.triangle_upper[i].push_back(exact ? sd : kInfinity);
          vb.triangle_lower[i].push_back(exact || !std::isfinite(sd) ? sd : sd * rng.uniform(0.25, 1.0));
        }
      for (int threads : {1, 3}) {
        const auto got = intra_object_distance(frame, boxes, ring2, IntraDistanceOptions{threads, &vb});
        expect_same_intra(got, ref, "threads " + std::to_string(threads));
        expect_candidates_accounted(got.counters, name);
        culled += got.counters.intra_voronoi_culled;
      }
    }
  }
  EXPECT_GT(culled, 0u);
}

TEST(IntraStage2, DefaultGridFollowsTheMedianTriangleInCrowds) {
  EXPECT_EQ(default_self_grid_resolution(18484, 2.65, 0.0195), 136);  // sqrt(n) when the triangles allow it
  EXPECT_EQ(default_self_grid_resolution(360000, 37.4, 0.2), 267);    // 37.4 / (0.7 * 0.2), below sqrt(n) = 600
  EXPECT_EQ(default_self_grid_resolution(360000, 1.0, 1.0), 32);      // clamped below
  EXPECT_EQ(default_self_grid_resolution(4000000, 1e6, 1e-6), 512);   // and above
  // A crowd of 1,000 small blobs (32 triangles each): the chosen grid follows their triangles,
  // and the answers hold.
  Frame frame;
  Rng rng(5);
  for (int k = 0; k < 1000; ++k)
    frame.objects.push_back(test::make_blob(rng, rng.vec3(0, 30), 0.5, 1, 0.1, "b" + std::to_string(k)));
  const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
  const auto ring2 = ring2_upper_bounds(frame, 2);
  auto backend = make_cpu_self_voronoi_backend(2);
  const SelfVoronoiBounds vb = compute_self_voronoi_bounds(frame, boxes, ring2, *backend, 0, 2);
  const int longest = std::max({vb.grid.dims[0], vb.grid.dims[1], vb.grid.dims[2]});
  // sqrt(32,000 triangles) = 179 cells; triangle boxes about 0.37 across in a box of about 31
  // give about 31 / (0.7 * 0.37) = 120.
  EXPECT_LT(longest, 140);
  EXPECT_GE(longest, 32);
  const auto ref = intra_object_distance_brute_force(frame);
  expect_same_intra(intra_object_distance(frame, boxes, ring2, IntraDistanceOptions{2, &vb}), ref, "crowd, default grid");
}

// The self grid depends on the frame alone, not on which objects the caller leaves out (static
// objects whose results it reuses): a large object left out still sets the box, the default
// resolution's triangle count and its median size, so the other objects get the same grid,
// the same samples and the same bounds as when nothing is left out. (With the object out of
// the box, funnel's frames after the first were sampled at cells of 0.023 instead of 0.054
// at --grid 256.)
TEST(IntraStage2, ObjectsLeftOutStillSetTheGrid) {
  Rng rng(11);
  Frame frame;
  frame.objects.push_back(test::make_blob(rng, Vec3(0, 0, 0), 4.0, 2, 0.1, "container"));
  frame.objects.push_back(test::make_blob(rng, Vec3(0.5, 0.2, 0), 0.6, 2, 0.4, "a"));
  frame.objects.push_back(test::make_blob(rng, Vec3(-0.8, 0.3, 0.2), 0.5, 1, 0.4, "b"));
  const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
  const std::vector<std::uint8_t> skip = {1, 0, 0};
  const auto ring2_all = ring2_upper_bounds(frame, 2);
  const auto ring2_skip = ring2_upper_bounds(frame, 2, &skip);
  auto backend = make_cpu_self_voronoi_backend(2);
  for (int grid : {0, 48, 160}) {
    SCOPED_TRACE("grid " + std::to_string(grid));
    const SelfVoronoiBounds all = compute_self_voronoi_bounds(frame, boxes, ring2_all, *backend, grid, 2);
    const SelfVoronoiBounds part = compute_self_voronoi_bounds(frame, boxes, ring2_skip, *backend, grid, 2, &skip);
    EXPECT_EQ(part.grid.dims, all.grid.dims);
    EXPECT_EQ(part.grid.cell, all.grid.cell);
    EXPECT_EQ(part.delta, all.delta);
    for (size_t i = 1; i < 3; ++i) {
      EXPECT_EQ(part.triangle_lower[i], all.triangle_lower[i]) << "object " << i;
      EXPECT_EQ(part.triangle_upper[i], all.triangle_upper[i]) << "object " << i;
    }
    // The container is not sampled: no bound of its triangles changes.
    for (double v : part.triangle_lower[0]) EXPECT_EQ(v, -kInfinity);
    EXPECT_LE(part.sampled_triangles, all.sampled_triangles);
    EXPECT_GT(part.sampled_triangles, 0u);
    const auto ref = intra_object_distance_brute_force(frame);
    IntraDistanceOptions opts{2, &part, &skip};
    const auto got = intra_object_distance(frame, boxes, ring2_skip, opts);
    for (size_t i = 1; i < 3; ++i) {
      ASSERT_EQ(got.per_object[i].per_triangle.size(), ref.per_object[i].per_triangle.size());
      for (size_t t = 0; t < ref.per_object[i].per_triangle.size(); ++t) {
        EXPECT_EQ(got.per_object[i].per_triangle[t].distance, ref.per_object[i].per_triangle[t].distance);
        EXPECT_EQ(got.per_object[i].per_triangle[t].nearest, ref.per_object[i].per_triangle[t].nearest);
      }
    }
  }
}

// Only triangles whose 2-ring bound exceeds 2δ get samples (kSelfSampleRing2OverDelta: below
// δ Stage II cannot lower their D_u, and up to 2δ it rarely gains anything), and that have a
// non-adjacent triangle at all (not a tetrahedron's faces); the others keep D_u = 2-ring bound
// and D_l = -inf. Both kinds occur, and Stage II still culls candidates on these scenes.
TEST(IntraStage2, OnlyTrianglesWhoseRing2BoundExceedsTwiceDeltaAreSampled) {
  std::uint64_t sampled = 0, unsampled = 0, culled = 0;
  for_each_recorded_run([&](const Frame& frame, const FrameBoxes& boxes, const std::vector<std::vector<double>>& ring2,
                            const SelfVoronoiBounds& vb, const Recorder& rec) {
    size_t total = 0;
    for (const auto& r : ring2) total += r.size();
    std::vector<char> has_samples(total, 0);  // stays empty when no triangle is sampled
    const std::vector<size_t> global_of = frame_triangles_of(frame, rec.input);
    for (const std::int32_t t : rec.input.sample_triangle) has_samples[global_of[static_cast<size_t>(t)]] = 1;
    std::uint64_t here = 0;
    size_t global = 0;
    for (size_t i = 0; i < frame.objects.size(); ++i) {
      const size_t n = ring2[i].size();
      const bool has_pairs = n >= 2;
      for (size_t t = 0; t < n; ++t) {
        const bool want = has_pairs && ring2[i][t] > kSelfSampleRing2OverDelta * vb.delta &&
                          test::has_non_adjacent(frame.objects[i], static_cast<Index>(t));
        const bool got = has_pairs && has_samples[global + t] != 0;
        ASSERT_EQ(got, want) << "object " << i << " triangle " << t;
        if (!want) {
          EXPECT_EQ(vb.triangle_upper[i][t], ring2[i][t]);
          EXPECT_EQ(vb.triangle_lower[i][t], -kInfinity);
        }
        here += want;
        (want ? sampled : unsampled) += 1;
      }
      global += n;
    }
    EXPECT_EQ(vb.sampled_triangles, here);
    IntraDistanceOptions opts{2, &vb};
    culled += intra_object_distance(frame, boxes, ring2, opts).counters.intra_voronoi_culled;
  });
  EXPECT_GT(sampled, 1000u);
  EXPECT_GT(unsampled, 1000u);
  EXPECT_GT(culled, 0u);
}

// The CPU self backend against its per-sample brute force over the whole frame, bitwise: every
// sample's value is the smallest double distance from the voxel centre to a triangle of the
// same object sharing no vertex with the sample's triangle, rounded to float, or the band when
// none is below it. (Its bin walk, first-visit rule and cut-offs only skip work, and so does
// leaving out of its input the triangles no sample's walk reaches.)
TEST(IntraStage2, CpuBackendEqualsPerSampleBruteForce) {
  std::uint64_t samples = 0, below_band = 0, runs = 0, partial = 0;
  for_each_recorded_run([&](const Frame& frame, const FrameBoxes&, const std::vector<std::vector<double>>&,
                            const SelfVoronoiBounds& vb, const Recorder& rec) {
    const DvdInput& in = rec.input.dvd;
    ASSERT_EQ(rec.output.dist.size(), in.voxels.size());
    // The frame's triangles in the backend's coordinates, as Stage II computes them (the unit
    // is a power of two: vb.grid.cell / in.grid.cell is exact).
    const double unit = vb.grid.cell / in.grid.cell;
    size_t total = 0;
    for (const Object& o : frame.objects) total += static_cast<size_t>(o.num_triangles());
    ++runs;
    partial += in.tri_site.size() < total;
    for (std::size_t k = 0; k < in.voxels.size(); ++k) {
      const auto f = static_cast<std::size_t>(rec.input.sample_triangle[k]);
      const Object& o = frame.objects[static_cast<size_t>(in.tri_site[f])];
      const std::int64_t id = in.voxels[k], dx = in.grid.dims[0], dy = in.grid.dims[1];
      const Vec3 q = in.grid.cell * Vec3(static_cast<double>(id % dx) + 0.5, static_cast<double>((id / dx) % dy) + 0.5,
                                         static_cast<double>(id / (dx * dy)) + 0.5);
      double best = kInfinity;
      for (Index t = 0; t < o.num_triangles(); ++t) {
        const Face& face = o.topology->faces[static_cast<size_t>(t)];
        bool adjacent = false;
        for (std::size_t a = 0; a < 3; ++a)
          for (std::size_t b = 0; b < 3; ++b) adjacent = adjacent || rec.input.tri_vertices[3 * f + a] == face[b];
        if (adjacent) continue;
        Triangle tri = o.triangle(t);
        for (Vec3& p : tri)
          for (int c = 0; c < 3; ++c) p[c] = (p[c] - vb.grid.origin[c]) / unit;
        best = std::min(best, std::sqrt(point_triangle_distance(q, tri).squared_distance));
      }
      const float want = best < in.band[k] ? static_cast<float>(best) : in.band[k];
      ASSERT_EQ(rec.output.dist[k], want) << "sample " << k;
      ++samples;
      below_band += best < in.band[k];
    }
  });
  // Many samples find a triangle below their band: the comparison is not only of bands; and
  // in many runs the backend got only part of the frame's triangles.
  EXPECT_GT(samples, 10000u);
  EXPECT_GT(below_band, samples / 4);
  EXPECT_GT(4 * partial, runs);
}

}  // namespace
}  // namespace vproxq
