// Formats read through assimp, and a cross-check of the project's PLY reader against assimp.
#include "io/assimp_reader.hpp"
#include "io/mesh_reader.hpp"
#include "io_test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace vproxq {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

// assimp stores positions as float: each coordinate of ours, rounded to float, may differ
// from assimp's by at most half an ulp of float, i.e. |a - b| <= 2^-24 |a| (we allow 2^-23).
constexpr double kFloatRounding = std::numeric_limits<float>::epsilon();

TEST(AssimpReader, PlyReaderAgreesWithAssimpOnTestData) {
  int checked = 0;
  for (const auto& entry :
       fs::recursive_directory_iterator(fs::path(VPROXQ_TEST_DATA_DIR) / "meshes")) {
    if (entry.path().extension() != ".ply") continue;
    SCOPED_TRACE(entry.path().string());
    const std::vector<MeshGroup> ours = read_mesh_file(entry.path());
    const std::vector<MeshGroup> theirs = io_detail::read_with_assimp(entry.path());
    ASSERT_EQ(ours.size(), 1u);
    ASSERT_EQ(theirs.size(), 1u);
    EXPECT_EQ(ours[0].faces, theirs[0].faces);
    ASSERT_EQ(ours[0].positions.size(), theirs[0].positions.size());
    for (std::size_t v = 0; v < ours[0].positions.size(); ++v) {
      for (int a = 0; a < 3; ++a) {
        const double x = ours[0].positions[v][a];
        const double y = theirs[0].positions[v][a];
        EXPECT_LE(std::abs(x - y), kFloatRounding * std::abs(x)) << "vertex " << v << " axis " << a;
      }
    }
    ++checked;
  }
  EXPECT_GE(checked, 7);  // two-cubes x3, cube, height-field, thick-cloth x2
}

TEST(AssimpReader, StlKeepsOneVertexPerCornerWithoutWelding) {
  TempDir dir;
  const auto file = dir.write("soup.stl",
                              "solid soup\n"
                              "facet normal 0 0 1\nouter loop\n"
                              "vertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                              "endloop\nendfacet\n"
                              "facet normal 0 0 1\nouter loop\n"
                              "vertex 1 0 0\nvertex 1 1 0\nvertex 0 1 0\n"
                              "endloop\nendfacet\n"
                              "endsolid soup\n");
  const auto groups = read_mesh_file(file);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].name, "soup");
  // STL is a triangle soup; no JoinIdenticalVertices, so shared corners stay apart.
  EXPECT_EQ(groups[0].positions.size(), 6u);
  EXPECT_EQ(groups[0].faces, (std::vector<Face>{{0, 1, 2}, {3, 4, 5}}));
  EXPECT_EQ(groups[0].positions[4], Vec3(1, 1, 0));
}

TEST(AssimpReaderErrors, MissingUnreadableAndUnknownFiles) {
  TempDir dir;
  const auto missing = dir.path() / "nothing.stl";
  EXPECT_INPUT_ERROR(read_mesh_file(missing), missing.string() + ": file not found");
  const auto garbage = dir.write("garbage.stl", "this is not an STL file\n");
  EXPECT_INPUT_ERROR(read_mesh_file(garbage), garbage.string() + ": assimp: ");
  const auto unknown = dir.write("mesh.xyz123", "garbage\n");
  EXPECT_INPUT_ERROR(read_mesh_file(unknown),
                     unknown.string() + ": assimp: ", "No suitable reader");
  EXPECT_INPUT_ERROR(read_mesh_file(dir.path()), dir.path().string() + ": is not a regular file");
}

}  // namespace
}  // namespace vproxq
