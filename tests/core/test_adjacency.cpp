// Adjacency (1-ring, 2-ring, edges) against definitions evaluated pair by pair.
#include "core/mesh/adjacency.hpp"
#include "support/random_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <set>

namespace vproxq {
namespace {


/// The rings by their definitions, O(T^2). Counts how many triangles have a hub (a vertex of
/// valence above Adjacency::kRingWalkValence) in their 1-ring, in `hubs_near`.
void check_against_definitions(const Topology& topo, int& hubs_near) {
  hubs_near = 0;
  const Adjacency& adj = adjacency(topo);
  const Index nt = topo.num_triangles();
  for (Index t = 0; t < nt; ++t) {
    std::vector<Index> r1, r2;
    for (Index g = 0; g < nt; ++g)
      if (g != t && Adjacency::share_vertex(topo.faces[static_cast<size_t>(t)], topo.faces[static_cast<size_t>(g)]))
        r1.push_back(g);
    for (Index g = 0; g < nt; ++g) {
      if (g == t || std::binary_search(r1.begin(), r1.end(), g)) continue;
      bool via = false;
      for (Index h : r1) via = via || Adjacency::share_vertex(topo.faces[static_cast<size_t>(h)], topo.faces[static_cast<size_t>(g)]);
      if (via) r2.push_back(g);
    }
    ASSERT_EQ(adj.ring1(t), r1) << "triangle " << t;
    ASSERT_EQ(adj.ring2(t), r2) << "triangle " << t;
    // ring2_vertices(): the 2-ring's vertices, or part of them when a hub is near t.
    std::set<Index> v2;
    for (Index g : r2)
      for (Index v : topo.faces[static_cast<size_t>(g)]) v2.insert(v);
    const std::vector<Index> walked(adj.ring2_vertices(t).begin(), adj.ring2_vertices(t).end());
    ASSERT_TRUE(std::is_sorted(walked.begin(), walked.end()));
    ASSERT_TRUE(std::adjacent_find(walked.begin(), walked.end()) == walked.end());
    for (Index v : walked) ASSERT_TRUE(v2.count(v)) << "triangle " << t << " vertex " << v;
    bool hub_near = false;
    for (Index g : r1)
      for (Index v : topo.faces[static_cast<size_t>(g)])
        hub_near = hub_near || adj.vertex_triangles(v).size() > Adjacency::kRingWalkValence;
    if (!hub_near) {
      ASSERT_EQ(walked, std::vector<Index>(v2.begin(), v2.end())) << "triangle " << t;
    }
    hubs_near += hub_near;
  }
  std::set<std::pair<Index, Index>> edges;
  for (const Face& f : topo.faces)
    for (int k = 0; k < 3; ++k) {
      const Index a = f[static_cast<size_t>(k)], b = f[static_cast<size_t>((k + 1) % 3)];
      if (a != b) edges.insert({std::min(a, b), std::max(a, b)});
    }
  ASSERT_EQ(adj.edges().size(), edges.size());
  for (size_t e = 0; e < adj.edges().size(); ++e) {
    const auto& [a, b] = adj.edges()[e];
    EXPECT_LT(a, b);
    EXPECT_TRUE(edges.count({a, b}));
    if (e > 0) {
      const auto& p = adj.edges()[e - 1];
      EXPECT_TRUE(p[1] < b || (p[1] == b && p[0] < a)) << "edges sorted by (b, a)";
    }
    EXPECT_EQ(adj.find_edge(b, a), static_cast<Index>(e));
    for (Index t : adj.edge_triangles(static_cast<Index>(e))) {
      const Face& f = topo.faces[static_cast<size_t>(t)];
      EXPECT_TRUE(std::count(f.begin(), f.end(), a) && std::count(f.begin(), f.end(), b));
    }
  }
  for (Index v = 0; v < topo.num_vertices; ++v)
    for (Index t : adj.vertex_triangles(v)) {
      const Face& f = topo.faces[static_cast<size_t>(t)];
      EXPECT_TRUE(std::count(f.begin(), f.end(), v));
    }
}

TEST(Adjacency, RandomBlobsMatchDefinitions) {
  test::Rng rng(7);
  for (int k = 0; k < 3; ++k) {
    const Object o = test::make_blob(rng, Vec3::Zero(), 1.0, 1, 0.3, "b");
    int hubs_near = 0;
    check_against_definitions(*o.topology, hubs_near);
    EXPECT_EQ(hubs_near, 0);
  }
}

TEST(Adjacency, IrregularMeshes) {
  // A strip with a boundary, a non-manifold fan of 3 triangles on edge (0,1), a duplicate
  // triangle, a degenerate face and an isolated vertex (9).
  Topology topo;
  topo.num_vertices = 10;
  topo.faces = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}, {2, 1, 5}, {2, 1, 5}, {5, 6, 7}, {7, 8, 8}, {6, 7, 8}};
  int hubs_near = 0;
  check_against_definitions(topo, hubs_near);
  EXPECT_EQ(hubs_near, 0);
  const Adjacency& adj = adjacency(topo);
  EXPECT_EQ(adj.edge_triangles(adj.find_edge(0, 1)).size(), 3u);  // non-manifold edge
  EXPECT_TRUE(adj.vertex_triangles(9).empty());                   // isolated vertex
  EXPECT_EQ(adj.triangle_edges(6)[1], kNoIndex);                  // (8, 8) is no edge
  EXPECT_EQ(adj.find_edge(3, 9), kNoIndex);
}

TEST(Adjacency, HighValenceHubs) {
  // A disc of 150 triangles around one vertex (valence 150), ringed by a strip of quads, and a
  // closed fan (a cone with its apex and a base hub): the 1-ring of a hub triangle is the
  // whole fan, and the 2-ring is reached only through the rim vertices.
  Topology disc;
  const Index n = 150;
  disc.num_vertices = 1 + 2 * n;
  for (Index k = 0; k < n; ++k) {
    const Index a = 1 + k, b = 1 + (k + 1) % n, a2 = 1 + n + k, b2 = 1 + n + (k + 1) % n;
    disc.faces.push_back({0, a, b});
    disc.faces.push_back({a, a2, b2});
    disc.faces.push_back({a, b2, b});
  }
  int hubs_near = 0;
  check_against_definitions(disc, hubs_near);
  EXPECT_GT(hubs_near, 0);
  Topology cone;
  cone.num_vertices = 2 + n;
  for (Index k = 0; k < n; ++k) {
    cone.faces.push_back({0, 2 + k, 2 + (k + 1) % n});
    cone.faces.push_back({1, 2 + (k + 1) % n, 2 + k});
  }
  check_against_definitions(cone, hubs_near);
  EXPECT_GT(hubs_near, 0);
  EXPECT_TRUE(adjacency(disc).ring2(0).size() > 0);
  // The rest of the apex fan (n - 1) and the 3 base triangles at its two rim vertices.
  EXPECT_EQ(adjacency(cone).ring1(0).size(), static_cast<size_t>(n + 2));
}

TEST(Adjacency, CachedPerTopologyAndResetOnCopy) {
  Topology topo;
  topo.num_vertices = 4;
  topo.faces = {{0, 1, 2}, {0, 2, 3}};
  const Adjacency* a = &adjacency(topo);
  EXPECT_EQ(a, &adjacency(topo));
  Topology copy = topo;
  copy.faces.push_back({1, 2, 3});
  EXPECT_EQ(adjacency(copy).ring1(2).size(), 2u);
  EXPECT_EQ(adjacency(topo).ring1(0).size(), 1u);
}

}  // namespace
}  // namespace vproxq
