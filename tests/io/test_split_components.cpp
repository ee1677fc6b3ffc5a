// split_components: connected components by shared vertices.
#include "io/mesh_reader.hpp"

#include <gtest/gtest.h>

#include <set>

namespace vproxq {
namespace {

MeshGroup numbered_group(int num_vertices, std::vector<Face> faces) {
  MeshGroup g;
  g.name = "g";
  for (int i = 0; i < num_vertices; ++i) g.positions.push_back(Vec3(i, 0, 0));
  g.faces = std::move(faces);
  return g;
}

TEST(SplitComponents, OrderedByFirstFaceVerticesInGlobalOrderIsolatedDropped) {
  // Component A = {1, 3, 5, 6} (faces 1 and 3), component B = {0, 2, 4} (faces 0 and 2), the
  // first face belongs to B. Vertex 7 is isolated.
  const MeshGroup g = numbered_group(8, {{4, 2, 0}, {5, 3, 1}, {0, 2, 4}, {6, 5, 1}});
  const std::vector<MeshGroup> parts = split_components(g);
  ASSERT_EQ(parts.size(), 2u);
  EXPECT_EQ(parts[0].name, "g#0");
  EXPECT_EQ(parts[1].name, "g#1");
  EXPECT_EQ(parts[0].positions, (std::vector<Vec3>{{0, 0, 0}, {2, 0, 0}, {4, 0, 0}}));
  EXPECT_EQ(parts[0].faces, (std::vector<Face>{{2, 1, 0}, {0, 1, 2}}));
  EXPECT_EQ(parts[1].positions, (std::vector<Vec3>{{1, 0, 0}, {3, 0, 0}, {5, 0, 0}, {6, 0, 0}}));
  EXPECT_EQ(parts[1].faces, (std::vector<Face>{{2, 1, 0}, {3, 2, 0}}));
}

TEST(SplitComponents, SharingOneVertexIsConnected) {
  const MeshGroup g = numbered_group(5, {{0, 1, 2}, {2, 3, 4}});
  const auto parts = split_components(g);
  ASSERT_EQ(parts.size(), 1u);
  EXPECT_EQ(parts[0].positions, g.positions);
  EXPECT_EQ(parts[0].faces, g.faces);
}

TEST(SplitComponents, ChainsMergedLateStayOneComponent) {
  // Faces 0 and 1 look separate until face 2 joins them.
  const MeshGroup g = numbered_group(9, {{0, 1, 2}, {6, 7, 8}, {3, 4, 5}, {2, 3, 6}});
  const auto parts = split_components(g);
  ASSERT_EQ(parts.size(), 1u);
  EXPECT_EQ(parts[0].faces, g.faces);
}

TEST(SplitComponents, NoFacesNoComponents) {
  EXPECT_TRUE(split_components(numbered_group(3, {})).empty());
}

TEST(SplitComponents, TwoCubesFromTestData) {
  for (const char* name :
       {"two-cubes-far.ply", "two-cubes-close.ply", "two-cubes-intersecting.ply"}) {
    SCOPED_TRACE(name);
    const auto groups =
        read_mesh_file(std::filesystem::path(VPROXQ_TEST_DATA_DIR) / "meshes" / name);
    ASSERT_EQ(groups.size(), 1u);
    const auto parts = split_components(groups[0]);
    ASSERT_EQ(parts.size(), 2u);
    EXPECT_EQ(parts[0].faces.size() + parts[1].faces.size(), groups[0].faces.size());
    // These files hold isolated (interior) vertices; components keep only the used ones.
    std::set<Index> used_by_file;
    for (const Face& f : groups[0].faces) used_by_file.insert(f.begin(), f.end());
    EXPECT_LT(used_by_file.size(), groups[0].positions.size());
    EXPECT_EQ(parts[0].positions.size() + parts[1].positions.size(), used_by_file.size());
    for (const MeshGroup& p : parts) {
      // every vertex is used and every index is in range
      std::set<Index> used;
      for (const Face& f : p.faces) used.insert(f.begin(), f.end());
      EXPECT_EQ(used.size(), p.positions.size());
      EXPECT_EQ(*used.rbegin(), static_cast<Index>(p.positions.size()) - 1);
    }
  }
}

}  // namespace
}  // namespace vproxq
