// Discrete collisions: the list of intersecting triangle pairs equals the all-pairs brute
// force (exact triangle–triangle intersection) with and without Stage II bounds, for any
// thread count.
#include "core/geometry/predicates.hpp"
#include "core/geometry/triangle_box.hpp"
#include "core/mesh/adjacency.hpp"
#include "core/query/inter_distance.hpp"
#include "core/query/intersecting_pairs.hpp"
#include "core/voronoi/stage2.hpp"
#include "support/random_scene.hpp"
#include "support/self_meshes.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <memory>

namespace vproxq {
namespace {

using test::make_random_frame;
using test::make_soup;
using test::Rng;

size_t count_intra(const std::vector<IntersectingPair>& pairs) {
  size_t n = 0;
  for (const auto& p : pairs) n += p.object_a == p.object_b;
  return n;
}

/// Overlapping blobs (inter pairs) plus triangle soups (many intra pairs, no shared vertices).
Frame mixed_frame(std::uint64_t seed) {
  Frame frame = make_random_frame(seed, 2 + static_cast<int>(seed % 7), 1.0 + 0.4 * static_cast<double>(seed % 4), 1);
  Rng rng(seed * 77);
  for (int k = 0; k < 2; ++k)
    frame.objects.push_back(make_soup(rng, rng.vec3(0, 2), 0.5, 0.3, 25, "soup" + std::to_string(k)));
  return frame;
}

TEST(IntersectingPairs, RandomScenesEqualBruteForce) {
  size_t total_inter = 0, total_intra = 0;
  for (std::uint64_t seed = 1; seed <= 10; ++seed) {
    const Frame frame = mixed_frame(seed);
    const auto ref = intersecting_pairs_brute_force(frame);
    total_intra += count_intra(ref.pairs);
    total_inter += ref.pairs.size() - count_intra(ref.pairs);
    for (int threads : {1, 3}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + " threads " + std::to_string(threads));
      const auto got = intersecting_pairs(frame, {threads, nullptr, true});
      EXPECT_EQ(got.pairs, ref.pairs);
      EXPECT_LE(got.exact_tests, ref.exact_tests);
    }
    // Without intra pairs: exactly the inter-object part of the list.
    std::vector<IntersectingPair> inter_only;
    for (const auto& p : ref.pairs)
      if (p.object_a != p.object_b) inter_only.push_back(p);
    EXPECT_EQ(intersecting_pairs(frame, {2, nullptr, false}).pairs, inter_only);
    EXPECT_EQ(intersecting_pairs_brute_force(frame, false).pairs, inter_only);
  }
  // The scenes must exercise both kinds, or the comparison proves little.
  EXPECT_GT(total_inter, 50u);
  EXPECT_GT(total_intra, 50u);
}

TEST(IntersectingPairs, FanAroundAHubWithCrossingTrianglesEqualsBruteForce) {
  // 300 slivers around vertex 0 overlap each other's boxes at the hub; subtrees of slivers
  // only are skipped as all adjacent (TriangleBvh::node_common_vertices()). Triangles of the
  // same object cross the fan without touching the hub: their pairs must all be found.
  const int n = 300;
  auto topo = std::make_shared<Topology>();
  Object o;
  o.name = "fan";
  o.positions.push_back(Vec3::Zero());
  for (int k = 0; k < n; ++k) {
    const double a = 2 * M_PI * k / n;
    o.positions.emplace_back(std::cos(a), std::sin(a), 0.01 * std::sin(7 * a));
  }
  for (Index k = 0; k < n; ++k) topo->faces.push_back({0, 1 + k, 1 + (k + 1) % n});
  Rng rng(3);
  for (int c = 0; c < 12; ++c) {
    const Index base = static_cast<Index>(o.positions.size());
    const Vec3 at{rng.uniform(-0.7, 0.7), rng.uniform(-0.7, 0.7), 0};
    o.positions.push_back(at + Vec3{rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), -0.2});
    o.positions.push_back(at + Vec3{rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), 0.2});
    o.positions.push_back(at + Vec3{rng.uniform(-0.3, 0.3), rng.uniform(-0.3, 0.3), 0.25});
    topo->faces.push_back({base, base + 1, base + 2});
  }
  topo->num_vertices = static_cast<Index>(o.positions.size());
  o.topology = topo;
  Frame frame;
  frame.objects = {o};
  const auto ref = intersecting_pairs_brute_force(frame);
  EXPECT_GT(ref.pairs.size(), 12u);
  for (int threads : {1, 2}) {
    const auto got = intersecting_pairs(frame, {threads, nullptr, true});
    EXPECT_EQ(got.pairs, ref.pairs);
  }
}

// The plane test of the search (triangle_box.hpp) against exact orientation predicates: a box
// it rejects has all 8 corners strictly on the same side of the triangle's plane. Random
// triangles (some nearly degenerate) at scales 1e-8 to 1e8, far from the origin or not, and
// boxes placed across, beside and just off the plane.
TEST(TrianglePlane, RejectsOnlyBoxesStrictlyOnOneSide) {
  Rng rng(4711);
  int rejected = 0, close = 0;
  for (int q = 0; q < 200000; ++q) {
    const double scale = std::pow(10.0, rng.uniform(-8, 8));
    const double offset = q % 3 == 0 ? 0.0 : std::pow(10.0, rng.uniform(-8, 12)) * (q % 2 ? 1 : -1);
    auto point = [&]() -> Vec3 { return Vec3::Constant(offset) + scale * rng.vec3(-1, 1); };
    Triangle t{point(), point(), point()};
    if (q % 7 == 0) {
      const double along = rng.uniform(-1, 2);
      t[2] = t[0] + (t[1] - t[0]) * along + scale * 1e-12 * Vec3(rng.uniform(-1, 1), 0, 0);
    }
    // A box centred near the plane, at a distance from 0 to 10 box sizes off it.
    const Vec3 nrm = (t[1] - t[0]).cross(t[2] - t[0]);
    const double len = nrm.norm();
    Vec3 dir(1, 0, 0);
    if (len > 0) dir = nrm / len;
    const double size = scale * std::pow(10.0, rng.uniform(-6, 0));
    const double off = size * std::pow(10.0, rng.uniform(-9, 1)) * (q % 4 < 2 ? 1 : -1);
    const Vec3 c = t[0] + (t[1] - t[0]) * rng.uniform(0, 1) + dir * off;
    AABB box;
    box.extend(c - size * rng.vec3(0, 1));
    box.extend(c + size * rng.vec3(0, 1));
    if (!TrianglePlane(t).rejects(box)) continue;
    ++rejected;
    close += std::abs(off) < 2 * size;
    int sign = 0;
    for (int k = 0; k < 8; ++k) {
      const Vec3 corner((k & 1) ? box.hi.x() : box.lo.x(), (k & 2) ? box.hi.y() : box.lo.y(), (k & 4) ? box.hi.z() : box.lo.z());
      const int o = orient3d(t[0], t[1], t[2], corner);
      ASSERT_NE(o, 0) << "query " << q;
      if (k == 0) sign = o;
      ASSERT_EQ(o, sign) << "query " << q;
    }
  }
  EXPECT_GT(rejected, 10000);
  EXPECT_GT(close, 5000);
}

// Long slivers across a fine wavy sheet, as separate objects and inside the sheet's own object:
// each sliver's box covers a large part of the sheet, but only the triangles along the line
// where its plane cuts the sheet can touch it. The answers equal brute force, and the BVH
// nodes on one side of a sliver's plane are not entered (PlaneSide): the slivers add 1,685
// triangle tests to the sheet's own; 14,672 when the sheet's triangles searched for them.
TEST(IntersectingPairs, SliversAcrossAFineSheetTestOnlyNearTheirPlanes) {
  const int n = 40;
  std::vector<Vec3> p;
  std::vector<Face> faces;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x)
      p.emplace_back(double(x) / n, double(y) / n, 0.02 * std::sin(7.0 * x / n) * std::cos(5.0 * y / n));
  for (Index y = 0; y < n; ++y)
    for (Index x = 0; x < n; ++x) {
      const Index a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      faces.push_back({a, b, d});
      faces.push_back({a, d, c});
    }
  Rng rng(9);
  auto sliver = [&] {
    const double y0 = rng.uniform(0, 1), y1 = rng.uniform(0, 1), z0 = rng.uniform(-0.3, -0.1), z1 = rng.uniform(0.1, 0.3);
    const Vec3 a(rng.uniform(0, 0.2), y0, z0), b(rng.uniform(0.8, 1), y1, z1);
    return std::array<Vec3, 3>{a, b, b + Vec3(0, 0.002, 0.001)};
  };
  Frame alone;  // the sheet without slivers
  alone.objects.push_back(test::make_object(p, faces, "sheet"));
  const std::uint64_t sheet_tests = intersecting_pairs(alone, {1, nullptr, true}).exact_tests;
  for (int k = 0; k < 5; ++k) {  // inside the sheet's object
    const Index base = static_cast<Index>(p.size());
    for (const Vec3& v : sliver()) p.push_back(v);
    faces.push_back({base, base + 1, base + 2});
  }
  Frame frame;
  frame.objects.push_back(test::make_object(p, faces, "sheet"));
  for (int k = 0; k < 10; ++k) {
    const auto t = sliver();
    frame.objects.push_back(test::make_object({t[0], t[1], t[2]}, {{0, 1, 2}}, "sliver" + std::to_string(k)));
  }
  const auto ref = intersecting_pairs_brute_force(frame);
  size_t inter = 0;
  for (const auto& q : ref.pairs) inter += q.object_a != q.object_b;
  EXPECT_GE(inter, 10u);
  EXPECT_GE(ref.pairs.size() - inter, 5u);
  for (int threads : {1, 2}) {
    const auto got = intersecting_pairs(frame, {threads, nullptr, true});
    EXPECT_EQ(got.pairs, ref.pairs);
    EXPECT_LT(got.exact_tests - sheet_tests, 3000u);
    if (threads == 1)
      std::printf("[          ] tests with the 15 slivers: %llu more than the sheet alone\n",
                  static_cast<unsigned long long>(got.exact_tests - sheet_tests));
  }
}

// Nested shells around one centre with one off centre cutting through some of them: boxes
// contain each other, so box overlap pairs every shell with every other; the enclosure bound
// (object_broad_phase.hpp) leaves only the pairs that can touch, with the same answer.
TEST(IntersectingPairs, NestedShellsEqualBruteForce) {
  size_t found = 0;
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    Rng rng(seed);
    Frame frame;
    for (int k = 0; k < 6; ++k)
      frame.objects.push_back(test::make_blob(rng, Vec3(0, 0, 0), 1.0 + 0.35 * k, 2, 0.03, "shell" + std::to_string(k)));
    frame.objects.push_back(test::make_blob(rng, Vec3(0.5, 0.1, 0), 1.5, 2, 0.03, "off-centre"));
    const auto ref = intersecting_pairs_brute_force(frame, false);
    const auto got = intersecting_pairs(frame, {2, nullptr, false});
    EXPECT_EQ(got.pairs, ref.pairs) << "seed " << seed;
    found += ref.pairs.size();
  }
  EXPECT_GT(found, 0u);
}

TEST(IntersectingPairs, CanonicalOrder) {
  const Frame frame = mixed_frame(4);
  const auto got = intersecting_pairs(frame, {2, nullptr, true});
  ASSERT_FALSE(got.pairs.empty());
  for (size_t k = 0; k < got.pairs.size(); ++k) {
    const auto& p = got.pairs[k];
    EXPECT_LE(p.object_a, p.object_b);
    if (p.object_a == p.object_b) {
      EXPECT_LT(p.tri_a, p.tri_b);
      EXPECT_FALSE(Adjacency::share_vertex(frame.objects[static_cast<size_t>(p.object_a)].topology->faces[static_cast<size_t>(p.tri_a)],
                                           frame.objects[static_cast<size_t>(p.object_a)].topology->faces[static_cast<size_t>(p.tri_b)]));
    }
    if (k > 0) {
      EXPECT_TRUE(got.pairs[k - 1] < p);
    }
  }
}

TEST(IntersectingPairs, WithCpuVoronoiBoundsEqualBruteForce) {
  auto backend = make_cpu_voronoi_backend(2);
  for (std::uint64_t seed = 11; seed <= 16; ++seed) {
    const Frame frame = mixed_frame(seed);
    const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
    const ObjectBroadPhase stage1 = object_broad_phase(frame, boxes, 2);
    const auto ref = intersecting_pairs_brute_force(frame);
    for (int grid : {16, 48}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + " grid " + std::to_string(grid));
      const VoronoiBounds vb = compute_voronoi_bounds(frame, boxes, stage1, *backend, grid, 2);
      const auto got = intersecting_pairs(frame, boxes, {2, &vb, true});
      EXPECT_EQ(got.pairs, ref.pairs);
    }
  }
}

TEST(IntersectingPairs, WithTheInterObjectDistancesEqualBruteForce) {
  // The run passes each object's distance to its nearest other object: pairs with an object
  // at positive distance from all others are skipped. Same list; fewer tests where a skipped
  // pair's boxes overlap.
  std::uint64_t tests_with = 0, tests_without = 0;
  int apart = 0;
  for (std::uint64_t seed = 1; seed <= 16; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Frame frame = mixed_frame(seed);
    const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
    std::vector<double> distance;
    for (const auto& d : inter_object_distance(frame, {2, nullptr}).per_object) {
      distance.push_back(d.distance);
      apart += d.distance > 0;
    }
    const auto ref = intersecting_pairs_brute_force(frame);
    IntersectingPairsOptions opts{2, nullptr, true};
    tests_without += intersecting_pairs(frame, boxes, opts).exact_tests;
    opts.object_distance = &distance;
    const auto got = intersecting_pairs(frame, boxes, opts);
    EXPECT_EQ(got.pairs, ref.pairs);
    tests_with += got.exact_tests;
  }
  EXPECT_GT(apart, 10);
  EXPECT_LT(tests_with, tests_without);
}

TEST(IntersectingPairs, SeparatedAndTouchingObjects) {
  // Two single triangles: apart, then sharing exactly one point (touching counts).
  auto tri_object = [](const Triangle& t, const std::string& name) {
    auto topo = std::make_shared<Topology>();
    topo->num_vertices = 3;
    topo->faces = {Face{0, 1, 2}};
    Object o;
    o.name = name;
    o.topology = topo;
    o.positions = {t[0], t[1], t[2]};
    return o;
  };
  Frame frame;
  frame.objects.push_back(tri_object({Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 1, 0)}, "a"));
  frame.objects.push_back(tri_object({Vec3(0.25, 0.25, 1e-12), Vec3(1, 1, 1), Vec3(0, 1, 1)}, "b"));
  EXPECT_TRUE(intersecting_pairs(frame, {1}).pairs.empty());
  frame.objects[1].positions[0].z() = 0;  // vertex of b on the interior of a
  const auto got = intersecting_pairs(frame, {1});
  ASSERT_EQ(got.pairs.size(), 1u);
  EXPECT_EQ(got.pairs[0], (IntersectingPair{0, 0, 1, 0}));
}

}  // namespace
}  // namespace vproxq
