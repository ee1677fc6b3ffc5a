// The CCD pipeline (core/query/ccd.hpp) against its brute-force twin on seeded random steps:
// identical vertex–face and edge–edge lists (ids and TOIs), per-pair summaries, independent of
// the thread count and of Stage II (voxel culling at several grid resolutions); skipping of
// objects whose topology changes; the exclusions of incident primitive pairs.
#include <gtest/gtest.h>

#include <Eigen/Geometry>

#include "core/geometry/ccd.hpp"
#include "core/query/ccd.hpp"
#include "core/voronoi/ccd_stage2.hpp"
#include "support/expect_same.hpp"
#include "support/random_scene.hpp"
#include "support/self_meshes.hpp"

#include <cmath>
#include <cstdio>

namespace vproxq {
namespace {

using test::expect_same_ccd;
using test::moved;

TEST(CcdPipeline, RandomStepsEqualBruteForceWithEveryCulling) {
  std::uint64_t inter = 0, intra = 0, tests_off = 0, tests_vox = 0, brute_tests = 0, separated = 0,
                separated_primitives = 0;
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Frame from = test::make_random_frame(seed, 5, 3.0, 1);
    from.index = 0;
    const Frame to = moved(from, seed * 31, 0.6, seed % 2 ? 0.25 : 0.05);
    const CcdStepResult ref = continuous_collisions_brute_force(from, to);
    EXPECT_EQ(ref.counters.limit_hits, 0u);
    brute_tests += ref.counters.elementary_tests();
    for (const auto& p : ref.pairs) (p.objects[0] == p.objects[1] ? intra : inter) += p.primitive_pairs;
    for (int threads : {1, 3}) {
      const CcdStepResult r = continuous_collisions(from, to, CcdOptions{threads, nullptr});
      expect_same_ccd(r, ref);
      if (threads == 1) tests_off += r.counters.elementary_tests();
      if (threads == 1) separated += r.counters.separated_pairs;
      if (threads == 1) separated_primitives += r.counters.separated_primitives;
      const CcdSweep sweep = CcdSweep::compute(from, to, threads);
      for (int grid : {4, 16, 64}) {
        SCOPED_TRACE("grid " + std::to_string(grid));
        const CcdVoxelCulling voxels(from, to, sweep, grid, threads);
        const CcdStepResult v = continuous_collisions(from, to, sweep, CcdOptions{threads, &voxels});
        expect_same_ccd(v, ref);
        if (threads == 1 && grid == 64) tests_vox += v.counters.elementary_tests();
      }
    }
  }
  // The scenes must exercise both kinds of collision, or the comparison proves little.
  EXPECT_GT(inter, 0u);
  EXPECT_GT(intra, 0u);
  // Candidate pairs whose swept boxes overlap but that a separating axis keeps apart for the
  // whole step are skipped, which the equality above checks loses nothing.
  EXPECT_GT(separated, 0u);
  // Likewise primitive pairs of the remaining triangle pairs.
  EXPECT_GT(separated_primitives, 0u);
  std::printf("[          ] colliding primitive pairs: inter %llu, intra %llu; elementary tests: "
              "brute force %llu, AABB culling %llu, voxels (grid 64) %llu; separated triangle "
              "pairs %llu, primitive pairs %llu\n",
              static_cast<unsigned long long>(inter), static_cast<unsigned long long>(intra),
              static_cast<unsigned long long>(brute_tests), static_cast<unsigned long long>(tests_off),
              static_cast<unsigned long long>(tests_vox), static_cast<unsigned long long>(separated),
              static_cast<unsigned long long>(separated_primitives));
}

TEST(CcdPipeline, TriangleSoupsEqualBruteForce) {
  // Soups: no shared vertices, so every triangle pair's 15 primitive pairs are candidates.
  test::Rng rng(5);
  Frame from;
  for (int i = 0; i < 3; ++i)
    from.objects.push_back(test::make_soup(rng, Vec3(i * 0.5, 0, 0), 0.6, 0.3, 40, "soup" + std::to_string(i)));
  const Frame to = moved(from, 9, 0.4, 0.2);
  const CcdStepResult ref = continuous_collisions_brute_force(from, to);
  EXPECT_GT(ref.vf.size() + ref.ee.size(), 0u);
  expect_same_ccd(continuous_collisions(from, to, CcdOptions{2, nullptr}), ref);
  const CcdSweep sweep = CcdSweep::compute(from, to, 2);
  const CcdVoxelCulling voxels(from, to, sweep, 32, 2);
  expect_same_ccd(continuous_collisions(from, to, sweep, CcdOptions{2, &voxels}), ref);
}

TEST(CcdPipeline, LargeCoordinateOffsetEqualsBruteForce) {
  Frame from = test::make_random_frame(11, 4, 2.5, 1);
  for (Object& o : from.objects)
    for (Vec3& p : o.positions) p += Vec3(1e5, -2e5, 3e5);
  const Frame to = moved(from, 12, 0.5, 0.2);
  const CcdStepResult ref = continuous_collisions_brute_force(from, to);
  EXPECT_GT(ref.vf.size() + ref.ee.size(), 0u);
  const CcdSweep sweep = CcdSweep::compute(from, to, 2);
  const CcdVoxelCulling voxels(from, to, sweep, 48, 2);
  expect_same_ccd(continuous_collisions(from, to, sweep, CcdOptions{2, &voxels}), ref);
}

TEST(CcdPipeline, AFarAwayObjectLeavesTheOthersMarginsAsTheyWere) {
  // Culling margins are per object pair (the kernel's δ depends on the query's own points):
  // an object parked a million units away must not widen the margins of the objects near the
  // origin. With one step-wide margin (1e-6 of the step's extent, here about 1) every
  // neighbouring triangle pair of the cluster was tested.
  const Frame cluster_from = test::make_random_frame(31, 4, 2.5, 1);
  const Frame cluster_to = moved(cluster_from, 32, 0.5, 0.2);
  Frame from = cluster_from, to = cluster_to;
  test::Rng rng(33);
  Object far = test::make_blob(rng, Vec3(1e6, 1e6, 1e6), 1.0, 1, 0.2, "far");
  from.objects.push_back(far);
  to.objects.push_back(far);
  const CcdStepResult ref = continuous_collisions_brute_force(from, to);
  EXPECT_GT(ref.vf.size() + ref.ee.size(), 0u);
  const CcdStepResult got = continuous_collisions(from, to, CcdOptions{2, nullptr});
  expect_same_ccd(got, ref);
  const CcdStepResult alone = continuous_collisions(cluster_from, cluster_to, CcdOptions{2, nullptr});
  EXPECT_EQ(got.counters.elementary_tests(), alone.counters.elementary_tests());
  Frame far_from, far_to;
  far_from.objects = {far};
  far_to.objects = {far};
  far_to.index = 1;
  const CcdStepResult far_alone = continuous_collisions(far_from, far_to, CcdOptions{2, nullptr});
  EXPECT_EQ(got.counters.triangle_pairs, alone.counters.triangle_pairs + far_alone.counters.triangle_pairs);
  const CcdSweep sweep = CcdSweep::compute(from, to, 2);
  EXPECT_GT(sweep.margin, 1.0);                // the step's: its extent is 1.7e6
  EXPECT_LT(sweep.pair_margin(0, 1), 1e-4);   // two objects of the cluster
  EXPECT_GT(sweep.pair_margin(0, 4), 1.0);    // with the far one
  // Stage II keeps using the step's margin; the answers stay the same.
  const CcdVoxelCulling voxels(from, to, sweep, 32, 2);
  expect_same_ccd(continuous_collisions(from, to, sweep, CcdOptions{2, &voxels}), ref);
}

// A ball flies through a fine sheet in one step, sideways as much as up: each ball triangle's
// path sweeps over many sheet triangles, and on the coordinate axes, the normals and the line
// through the centroids each of those is ahead at one end of the step and behind at the other.
// The axes perpendicular to the relative motion leave only the sheet triangles along the path.
TEST(CcdPipeline, AFastSidewaysPassThroughAFineSheetTestsOnlyAlongThePath) {
  const int n = 24;
  std::vector<Vec3> p;
  std::vector<Face> faces;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) p.emplace_back(2.0 * x / n - 1, 2.0 * y / n - 1, 0.0);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const Index a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      faces.push_back({a, b, d});
      faces.push_back({a, d, c});
    }
  test::Rng rng(51);
  Frame from, to;
  from.objects = {test::make_object(p, faces, "sheet"),
                  test::make_blob(rng, Vec3(-0.6, -0.6, -0.4), 0.25, 2, 0.0, "ball")};
  to.objects = from.objects;
  to.index = 1;
  for (Vec3& x : to.objects[1].positions) x += Vec3(1.2, 1.2, 0.8);
  const CcdStepResult ref = continuous_collisions_brute_force(from, to);
  ASSERT_GT(ref.vf.size() + ref.ee.size(), 100u);
  const CcdStepResult got = continuous_collisions(from, to, CcdOptions{2, nullptr});
  expect_same_ccd(got, ref);
  // Along the path only: 8,697 elementary tests for 1,036 colliding pairs (139,972 without the
  // perpendicular axes).
  EXPECT_LT(got.counters.elementary_tests(), 16 * (ref.vf.size() + ref.ee.size()));
}

// Two layers of a sheet 1e-5 apart (a cloth folded flat, or stacked): the kernel's δ for
// queries of two nearby triangles is about 1e-6 of their size (edges of 1 here), so the
// layers are far outside it and every pair between them is culled. A margin taken from the
// whole object (1e-6 of its size, 10) covered the gap, and every triangle pair of the two
// layers that overlap was tested.
TEST(CcdPipeline, LayersCloserThanTheObjectsMarginButApartAreCulled) {
  const int n = 10;
  std::vector<Vec3> p;
  std::vector<Face> faces;
  for (int layer = 0; layer < 2; ++layer) {
    const Index base = static_cast<Index>(p.size());
    for (int y = 0; y <= n; ++y)
      for (int x = 0; x <= n; ++x) p.emplace_back(x, y, layer * 1e-5);
    for (int y = 0; y < n; ++y)
      for (int x = 0; x < n; ++x) {
        const Index a = base + y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
        faces.push_back({a, b, d});
        faces.push_back({a, d, c});
      }
  }
  const size_t per_layer = p.size() / 2;
  Frame from, to;
  from.objects = {test::make_object(p, faces, "stack")};
  to.objects = from.objects;
  to.index = 1;
  for (size_t v = per_layer; v < p.size(); ++v) to.objects[0].positions[v].x() += 0.3;  // the top layer slides
  const CcdStepResult ref = continuous_collisions_brute_force(from, to);
  EXPECT_EQ(ref.counters.limit_hits, 0u);
  const CcdStepResult got = continuous_collisions(from, to, CcdOptions{2, nullptr});
  expect_same_ccd(got, ref);
  // The same step with each layer alone: no test between the layers is left.
  std::uint64_t alone = 0;
  for (int layer = 0; layer < 2; ++layer) {
    std::vector<Face> f(faces.begin() + layer * 2 * n * n, faces.begin() + (layer + 1) * 2 * n * n);
    Frame a, b;
    a.objects = {test::make_object(p, f, "layer")};
    b.objects = a.objects;
    b.objects[0].positions = to.objects[0].positions;
    b.index = 1;
    alone += continuous_collisions(a, b, CcdOptions{2, nullptr}).counters.elementary_tests();
  }
  EXPECT_EQ(got.counters.elementary_tests(), alone);
}

// Two sheets lying aslant, with normal (1, 1, 1), two objects 0.2 apart along it (triangles 1
// wide): every triangle's box overlaps many of the other sheet's and their hierarchies' boxes
// overlap throughout, but along that diagonal the sheets stay apart while the top one slides, so
// the other sheet's hierarchy is passed over at its root (Diagonals in ccd.cpp): no triangle
// pair across them is looked at.
TEST(CcdPipeline, SheetsAslantArePassedOverAlongTheDiagonals) {
  const int n = 10;
  const Vec3 u = test::AslantFrame{}.u;
  Frame from, to;
  for (int sheet = 0; sheet < 2; ++sheet)
    from.objects.push_back(test::make_aslant_sheet(n, sheet * 0.2, sheet == 0 ? "bottom" : "top"));
  const std::vector<Face>& faces = from.objects[0].topology->faces;
  to.objects = from.objects;
  to.index = 1;
  for (Vec3& x : to.objects[1].positions) x += 0.3 * u;  // the top sheet slides
  const CcdStepResult ref = continuous_collisions_brute_force(from, to);
  EXPECT_EQ(ref.counters.limit_hits, 0u);
  const CcdStepResult got = continuous_collisions(from, to, CcdOptions{2, nullptr});
  expect_same_ccd(got, ref);
  // Pairs across the sheets whose swept boxes overlap: what boxes alone would leave.
  auto swept = [&](Index object, const Face& f) {
    AABB b;
    for (Index k : f) {
      b.extend(from.objects[static_cast<size_t>(object)].positions[static_cast<size_t>(k)]);
      b.extend(to.objects[static_cast<size_t>(object)].positions[static_cast<size_t>(k)]);
    }
    return b;
  };
  std::uint64_t boxed = 0;
  for (const Face& f : faces)
    for (const Face& g : faces) boxed += boxes_overlap(swept(0, f), swept(1, g));
  EXPECT_GT(boxed, 1000u);
  // The pairs looked at are those within each sheet alone.
  std::uint64_t alone = 0;
  for (size_t sheet = 0; sheet < 2; ++sheet) {
    Frame a, b;
    a.objects = {from.objects[sheet]};
    b.objects = {to.objects[sheet]};
    b.index = 1;
    alone += continuous_collisions(a, b, CcdOptions{2, nullptr}).counters.triangle_pairs;
  }
  EXPECT_EQ(got.counters.triangle_pairs, alone) << boxed << " pairs across the sheets have overlapping boxes";
}

// A closed cylinder of n segments, its caps fans around a hub vertex, listed before its sides;
// it turns a little and rises over the step, and one rim vertex of the top cap is pushed down
// through the bottom cap (collisions with its triangles and edges). Every cap triangle's box
// holds the hub, so all
// cap triangles overlap each other; between two of them only primitives through the hub are
// left (excluded: they share it) once the rim belongs to the side triangles, so the search
// must not visit those pairs: 44,814 candidate triangle pairs at n = 200 before (n^2 per
// step, 64 M at n = 8,000, 3.7 s).
TEST(CcdPipeline, FansAroundAHubAreNotPairedWithEachOther) {
  const int n = 200;
  auto cylinder = [&](double turn, double rise) {
    std::vector<Vec3> p;
    for (int z = 0; z < 2; ++z)
      for (int k = 0; k < n; ++k) {
        const double a = 2 * M_PI * k / n + turn;
        p.emplace_back(std::cos(a), std::sin(a), z + rise);
      }
    p.emplace_back(0, 0, rise);
    p.emplace_back(0, 0, 1 + rise);
    return p;
  };
  const Index bottom = 2 * n, top = 2 * n + 1;
  std::vector<Face> faces;
  for (Index k = 0; k < n; ++k) {
    const Index next = (k + 1) % n;
    faces.push_back({bottom, next, k});
    faces.push_back({top, n + k, n + next});
  }
  for (Index k = 0; k < n; ++k) {
    const Index next = (k + 1) % n;
    faces.push_back({k, next, n + next});
    faces.push_back({k, n + next, n + k});
  }
  Frame from, to;
  from.objects = {test::make_object(cylinder(0, 0), faces, "cylinder")};
  to.objects = {test::make_object(cylinder(0.01, 0.01), faces, "cylinder")};
  to.objects[0].positions[static_cast<size_t>(n)] = Vec3(-0.5, 0.05, -0.3);
  to.index = 1;
  const CcdStepResult ref = continuous_collisions_brute_force(from, to);
  EXPECT_GT(ref.vf.size(), 0u);
  EXPECT_GT(ref.ee.size(), 0u);
  const CcdStepResult got = continuous_collisions(from, to, CcdOptions{2, nullptr});
  expect_same_ccd(got, ref);
  std::printf("[          ] colliding vf %zu, ee %zu; candidate triangle pairs %llu\n", ref.vf.size(), ref.ee.size(),
              static_cast<unsigned long long>(got.counters.triangle_pairs));
  EXPECT_LT(got.counters.triangle_pairs, 20u * faces.size());
}

// Vertices used by no face take no part: an unused vertex that one frame's file adds (or
// lacks) is no topology change, and the step's answer is that of the same step without it.
TEST(CcdPipeline, AnUnusedVertexInOneFrameOnlyChangesNothing) {
  const Frame from = test::make_random_frame(41, 3, 1.2, 1);
  Frame to = moved(from, 42, 0.5, 0.2);
  to.index = 1;
  const CcdStepResult plain = continuous_collisions_brute_force(from, to);
  ASSERT_GT(plain.vf.size() + plain.ee.size(), 0u);
  ASSERT_TRUE(plain.skipped.empty());
  auto with_extra = [](Frame f) {
    Object& o = f.objects[1];
    auto topo = std::make_shared<Topology>(*o.topology);
    topo->num_vertices += 1;
    o.topology = topo;
    o.positions.push_back(Vec3(50, 50, 50));
    return f;
  };
  for (const bool extra_at_end : {true, false}) {
    SCOPED_TRACE(extra_at_end ? "added in frame 1" : "dropped in frame 1");
    const Frame a = extra_at_end ? from : with_extra(from);
    const Frame b = extra_at_end ? with_extra(to) : to;
    const CcdStepResult got = continuous_collisions(a, b, CcdOptions{2, nullptr});
    EXPECT_TRUE(got.skipped.empty());
    expect_same_ccd(got, plain);
    const CcdSweep sweep = CcdSweep::compute(a, b, 2);
    const CcdVoxelCulling voxels(a, b, sweep, 32, 2);
    expect_same_ccd(continuous_collisions(a, b, sweep, CcdOptions{2, &voxels}), plain);
  }
}

TEST(CcdPipeline, TopologyChangeAndMissingObjectAreSkipped) {
  Frame from = test::make_random_frame(3, 3, 2.0, 1);
  Frame to = moved(from, 4, 0.5, 0.1);
  to.index = 1;
  // Object 1 fractures: a copied topology with one face dropped.
  auto topo = std::make_shared<Topology>(*to.objects[1].topology);
  topo->faces.pop_back();
  to.objects[1].topology = topo;
  // Object 2 keeps equal faces in a different Topology instance: not a change.
  to.objects[2].topology = std::make_shared<Topology>(*from.objects[2].topology);
  // A fourth object in frame 0 has no counterpart in frame 1.
  test::Rng rng(1);
  from.objects.push_back(test::make_blob(rng, Vec3(0, 0, 0), 0.5, 1, 0.1, "extra"));
  const CcdStepResult r = continuous_collisions(from, to, CcdOptions{2, nullptr});
  ASSERT_EQ(r.skipped.size(), 2u);
  EXPECT_EQ(r.skipped[0].object, 1);
  EXPECT_NE(r.skipped[0].reason.find("topology changes"), std::string::npos) << r.skipped[0].reason;
  EXPECT_EQ(r.skipped[1].object, 3);
  EXPECT_NE(r.skipped[1].reason.find("no counterpart"), std::string::npos) << r.skipped[1].reason;
  for (const auto& h : r.vf) {
    EXPECT_NE(h.object_v, 1);
    EXPECT_NE(h.object_f, 1);
    EXPECT_NE(h.object_v, 3);
  }
  expect_same_ccd(r, continuous_collisions_brute_force(from, to));
  EXPECT_EQ(r.to_frame, 1);
}

// Objects are matched by position; files that list the same objects in another order would
// pair unrelated vertices and report collisions where nothing moves. A name that merely
// changes (names taken from each frame's file name) is no mismatch.
TEST(CcdPipeline, ObjectsListedInAnotherOrderAreSkipped) {
  Frame from = test::make_random_frame(5, 3, 1.0, 1);
  from.index = 0;
  Frame to = from;
  to.index = 1;
  std::swap(to.objects[0], to.objects[1]);
  to.objects[2].name = "renamed";
  const CcdStepResult r = continuous_collisions(from, to, CcdOptions{2, nullptr});
  ASSERT_EQ(r.skipped.size(), 2u);
  EXPECT_EQ(r.skipped[0].object, 0);
  EXPECT_EQ(r.skipped[1].object, 1);
  EXPECT_NE(r.skipped[0].reason.find("'" + from.objects[0].name + "' is object 1 of frame 1"), std::string::npos)
      << r.skipped[0].reason;
  EXPECT_TRUE(r.vf.empty() && r.ee.empty());
  expect_same_ccd(r, continuous_collisions_brute_force(from, to));
}

// The CLI matches objects by name when the files list them in another order (or a breaking
// object's pieces are renumbered): CCD over the reordered next frame equals CCD over the same
// frame listed in the original order.
TEST(CcdPipeline, CounterpartsByNameFollowObjectsListedInAnotherOrder) {
  Frame from = test::make_random_frame(7, 4, 1.2, 1);
  from.index = 0;
  const Frame to = moved(from, 9, 0.5, 0.25);
  Frame shuffled = to;
  std::swap(shuffled.objects[0], shuffled.objects[3]);
  std::swap(shuffled.objects[1], shuffled.objects[2]);
  EXPECT_FALSE(ccd_counterparts(from, to).has_value());  // already in order
  const std::optional<Frame> aligned = ccd_counterparts(from, shuffled);
  ASSERT_TRUE(aligned.has_value());
  const CcdStepResult ref = continuous_collisions_brute_force(from, to);
  EXPECT_FALSE(ref.vf.empty() && ref.ee.empty());
  EXPECT_TRUE(ref.skipped.empty());
  expect_same_ccd(continuous_collisions(from, *aligned, CcdOptions{2, nullptr}), ref);

  // A name missing from the next frame: that object is skipped, the others are matched.
  Frame fewer = shuffled;
  fewer.objects.erase(fewer.objects.begin());  // to's object 3
  const std::optional<Frame> partial = ccd_counterparts(from, fewer);
  ASSERT_TRUE(partial.has_value());
  const CcdStepResult r = continuous_collisions(from, *partial, CcdOptions{2, nullptr});
  ASSERT_EQ(r.skipped.size(), 1u);
  EXPECT_EQ(r.skipped[0].object, 3);
  EXPECT_NE(r.skipped[0].reason.find("no object named"), std::string::npos) << r.skipped[0].reason;

  // A name given twice: no matching by name (objects are then matched by position).
  Frame twice = shuffled;
  twice.objects[1].name = twice.objects[0].name;
  EXPECT_FALSE(ccd_counterparts(from, twice).has_value());

  // Names that change with every frame (each file's name) and are found nowhere else: matched
  // by position, nothing skipped.
  Frame renamed = to;
  for (Object& o : renamed.objects) o.name += "-next";
  EXPECT_FALSE(ccd_counterparts(from, renamed).has_value());
}

TEST(CcdPipeline, IncidentPairsAreExcludedButNeighboursAreTested) {
  // Two triangles sharing vertex 0; the tip of the second (vertex 3) swings through the first.
  auto topo = std::make_shared<Topology>();
  topo->num_vertices = 4;
  topo->faces = {{0, 1, 2}, {0, 2, 3}};
  Object a;
  a.name = "hinge";
  a.topology = topo;
  a.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0), Vec3(0.4, 0.3, 1)};
  Object b = a;
  b.positions[3] = Vec3(0.3, 0.2, -1);
  Frame from, to;
  from.objects = {a};
  to.objects = {b};
  to.index = 1;
  const CcdStepResult r = continuous_collisions(from, to, CcdOptions{1, nullptr});
  // Vertex 3 crosses face 0 (it is not a corner of it): reported although the triangles are
  // adjacent. The incident pairs (vertex 0 or 2 against face 0, edges sharing a vertex) are not.
  ASSERT_EQ(r.vf.size(), 1u);
  EXPECT_EQ(r.vf[0].vertex, 3);
  EXPECT_EQ(r.vf[0].face, 0);
  EXPECT_GT(r.vf[0].toi, 0.45);
  EXPECT_LE(r.vf[0].toi, 0.5);
  // The only edge pair without a shared vertex is (1-2, 0-3); edge 0-3 sweeps through the
  // plane z = 0 only at points with x + y <= 0.7, never reaching edge 1-2 (x + y = 1).
  EXPECT_TRUE(r.ee.empty());
  expect_same_ccd(r, continuous_collisions_brute_force(from, to));
  ASSERT_EQ(r.pairs.size(), 1u);
  EXPECT_EQ(r.pairs[0].objects, (std::array<Index, 2>{0, 0}));
}

TEST(CcdPipeline, FacesWithARepeatedVertexTestEachPrimitivePairOnce) {
  // A face (a, a, b) lists vertex a twice and its one edge {a, b} twice; each primitive pair
  // is still tested and reported once, as the brute force (which walks vertices and edges)
  // does. Object 0 is such a face on the segment (0,0,0)-(1,0,0); object 1's edge crosses it
  // at t = 0.5, and object 0's vertex 1 drops through object 1's big triangle.
  auto seg = std::make_shared<Topology>();
  seg->num_vertices = 2;
  seg->faces = {{0, 0, 1}};
  auto tri = std::make_shared<Topology>();
  tri->num_vertices = 3;
  tri->faces = {{0, 1, 2}};
  Object a, b;
  a.name = "segment";
  a.topology = seg;
  a.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0)};
  b.name = "triangle";
  b.topology = tri;
  b.positions = {Vec3(0.5, -0.5, 0.5), Vec3(0.5, 0.5, 0.5), Vec3(0.5, 0, 1.5)};
  Object a1 = a, b1 = b;
  for (Vec3& p : b1.positions) p.z() -= 1.0;
  Frame from, to;
  from.objects = {a, b};
  to.objects = {a1, b1};
  to.index = 1;
  const CcdStepResult edges = continuous_collisions(from, to, CcdOptions{1, nullptr});
  ASSERT_EQ(edges.ee.size(), 1u);
  EXPECT_EQ(edges.ee[0].object_a, 0);
  EXPECT_EQ(edges.ee[0].object_b, 1);
  expect_same_ccd(edges, continuous_collisions_brute_force(from, to));

  Object floor = b;
  floor.positions = {Vec3(-5, -5, 0), Vec3(5, -5, 0), Vec3(0, 5, 0)};
  a.positions = {Vec3(0, 0, 1), Vec3(1, 0, 1)};
  a1.positions = {Vec3(0, 0, 1), Vec3(1, 0, -1)};
  from.objects = {a, floor};
  to.objects = {a1, floor};
  const CcdStepResult vertex = continuous_collisions(from, to, CcdOptions{1, nullptr});
  ASSERT_EQ(vertex.vf.size(), 1u);
  EXPECT_EQ(vertex.vf[0].vertex, 1);
  expect_same_ccd(vertex, continuous_collisions_brute_force(from, to));

  // Random scenes with a third of the faces collapsed onto one of their edges.
  std::size_t hits = 0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Frame f = test::make_random_frame(seed, 4, 1.5, 1);
    f.index = 0;
    for (Object& o : f.objects) {
      auto t = std::make_shared<Topology>(*o.topology);
      for (size_t k = 0; k < t->faces.size(); k += 3) t->faces[k][k % 2 == 0 ? 2 : 0] = t->faces[k][1];
      o.topology = t;
    }
    const Frame g = moved(f, seed * 17, 0.6, 0.25);
    const CcdStepResult ref = continuous_collisions_brute_force(f, g);
    hits += ref.vf.size() + ref.ee.size();
    expect_same_ccd(continuous_collisions(f, g, CcdOptions{2, nullptr}), ref);
  }
  EXPECT_GT(hits, 0u);
}

TEST(CcdPipeline, NearMissesWithinTheKernelToleranceAreKept) {
  // A triangle drops through the plane of a fixed one, its corner q passing a distance h
  // outside the fixed triangle's hypotenuse, h a fraction of the kernel's tolerance δ. The
  // kernel reports such pairs (they come within δ), so no culling may drop them although the
  // primitives never touch: a culling direction in the floor's plane across the hypotenuse
  // (which none of the separating-axis tests uses) would, unless it asked for a gap above the
  // culling margin.
  for (const double fraction : {0.05, 0.2, 0.9}) {
    SCOPED_TRACE("h = " + std::to_string(fraction) + " δ");
    auto floor_topo = std::make_shared<Topology>();
    floor_topo->num_vertices = 3;
    floor_topo->faces = {{0, 1, 2}};
    Object floor;
    floor.name = "floor";
    floor.topology = floor_topo;
    floor.positions = {Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)};
    // Every query's extent is at least 1, so δ >= 1e-6 (kCcdRelativeTolerance).
    const double s = fraction * 1e-6 / std::sqrt(2.0);
    const Vec3 q(0.5 + s, 0.5 + s, 0.5);
    Object dropper;
    dropper.name = "dropper";
    dropper.topology = std::make_shared<Topology>(*floor_topo);
    dropper.positions = {q, q + Vec3(1, 0, 0), q + Vec3(0, 1, 0)};
    Object dropped = dropper;
    for (Vec3& p : dropped.positions) p.z() -= 1.0;
    Frame from, to;
    from.objects = {floor, dropper};
    to.objects = {floor, dropped};
    to.index = 1;
    const CcdStepResult ref = continuous_collisions_brute_force(from, to);
    EXPECT_FALSE(ref.vf.empty() && ref.ee.empty()) << "the kernel reports no near miss here";
    for (int threads : {1, 2}) expect_same_ccd(continuous_collisions(from, to, CcdOptions{threads, nullptr}), ref);
  }
}

TEST(CcdPipeline, TrianglesAroundASharedVertexAreCulledAsAPairOnlyWhenApart) {
  // Two triangles of one object that share only the vertex c: f = (c, a, b) and g = (c, d, e).
  // Flat and apart on either side of a line through c, moving rigidly, the pair is shown apart
  // as a whole (one axis for all its primitive pairs) and nothing is tested. When g swings
  // through f (a real collision between them), or when g lies across f's sector from the
  // start, no axis through c separates them, and the result is the brute force's.
  const Eigen::Matrix3d turn =
      (Eigen::AngleAxisd(0.7, Vec3(0, 0, 1)) * Eigen::AngleAxisd(0.4, Vec3(1, 0, 0))).toRotationMatrix();
  auto at = [&](double x, double y, double z) { return Vec3(turn * Vec3(x, y, z) + Vec3(0.3, -0.2, 0.1)); };
  const Object o = test::make_object({at(0, 0, 0), at(1, 0.1, 0), at(0.8, 0.7, 0), at(-0.9, 0.5, 0), at(-0.8, -0.3, 0)},
                                     {{0, 1, 2}, {0, 3, 4}}, "fan");
  auto run = [&](const Object& start, const Object& end) {
    Frame from, to;
    from.objects = {start};
    to.objects = {end};
    to.index = 1;
    const CcdStepResult ref = continuous_collisions_brute_force(from, to);
    CcdStepResult got;
    for (int threads : {1, 2}) {
      got = continuous_collisions(from, to, CcdOptions{threads, nullptr});
      expect_same_ccd(got, ref);
    }
    return std::pair{got, ref};
  };
  {
    SCOPED_TRACE("apart, moving rigidly");
    Object next = o;
    for (Vec3& p : next.positions) p += Vec3(0.01, -0.02, 0.03);
    const auto [got, ref] = run(o, next);
    EXPECT_EQ(got.counters.triangle_pairs, 1u);
    EXPECT_EQ(got.counters.separated_pairs, 1u);
    EXPECT_EQ(got.counters.separated_primitives, 0u);
    EXPECT_EQ(got.counters.vf_tests + got.counters.ee_tests, 0u);
    EXPECT_TRUE(ref.vf.empty() && ref.ee.empty());
  }
  {
    SCOPED_TRACE("g swings through f");
    Object next = o;
    next.positions[3] = at(0.9, 0.6, 0.3);
    next.positions[4] = at(0.9, 0.2, -0.3);
    const auto [got, ref] = run(o, next);
    EXPECT_EQ(got.counters.separated_pairs, 0u);
    EXPECT_FALSE(ref.vf.empty() && ref.ee.empty()) << "no collision to find";
  }
  {
    SCOPED_TRACE("g across f's sector");
    Object start = o;
    start.positions[3] = at(0.5, 0.9, 0.2);
    start.positions[4] = at(0.6, -0.4, 0.2);
    Object next = start;
    for (Vec3& p : next.positions) p += Vec3(0.01, -0.02, 0.03);
    const auto [got, ref] = run(start, next);
    EXPECT_EQ(got.counters.separated_pairs, 0u);
  }
}

}  // namespace
}  // namespace vproxq
