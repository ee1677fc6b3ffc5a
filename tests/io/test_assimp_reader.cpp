// Formats read through assimp, and a cross-check of the project's PLY reader against assimp.
#include "io/assimp_reader.hpp"
#include "io/mesh_reader.hpp"
#include "io_test_util.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <map>
#include <string>
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

TEST(AssimpReader, StlCornersAtOnePositionAreWelded) {
  // STL stores each facet with its own three corners: read as they are, a closed mesh would
  // be a soup (intra-object distance 0 between neighbours, PD open_surface, one component per
  // triangle). Corners at the same position become one vertex, in the order of first use.
  TempDir dir;
  const auto file = dir.write("soup.stl",
                              "solid soup\n"
                              "facet normal 0 0 1\nouter loop\n"
                              "vertex 0 0 0\nvertex 1 0 0\nvertex 0 1 0\n"
                              "endloop\nendfacet\n"
                              "facet normal 0 0 1\nouter loop\n"
                              "vertex 1 0 0\nvertex 1 1 0\nvertex -0 1 0\n"
                              "endloop\nendfacet\n"
                              "facet normal 0 0 1\nouter loop\n"
                              "vertex 5 0 0\nvertex 6 0 0\nvertex 5 1e-30 0\n"
                              "endloop\nendfacet\n"
                              "endsolid soup\n");
  const auto groups = read_mesh_file(file);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].name, "soup");
  EXPECT_EQ(groups[0].faces, (std::vector<Face>{{0, 1, 2}, {1, 3, 2}, {4, 5, 6}}));
  ASSERT_EQ(groups[0].positions.size(), 7u);
  EXPECT_EQ(groups[0].positions[3], Vec3(1, 1, 0));
  EXPECT_EQ(groups[0].positions[6], Vec3(5, static_cast<double>(1e-30f), 0));  // not (5, 0, 0)

  // A closed box as 12 STL facets: 8 vertices, every edge used twice, so PD is defined.
  std::string stl = "solid box\n";
  const int quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  auto corner = [](int c) {
    return std::to_string(c & 1) + " " + std::to_string((c >> 1) & 1) + " " + std::to_string((c >> 2) & 1);
  };
  for (const auto& q : quads)
    for (const auto& tri : {std::array<int, 3>{q[0], q[1], q[2]}, std::array<int, 3>{q[0], q[2], q[3]}}) {
      stl += "facet normal 0 0 0\nouter loop\n";
      for (int c : tri) stl += "vertex " + corner(c) + "\n";
      stl += "endloop\nendfacet\n";
    }
  stl += "endsolid box\n";
  const auto box = read_mesh_file(dir.write("box.stl", stl));
  ASSERT_EQ(box.size(), 1u);
  EXPECT_EQ(box[0].positions.size(), 8u);
  EXPECT_EQ(box[0].faces.size(), 12u);
  std::map<std::pair<Index, Index>, int> directed;
  for (const Face& f : box[0].faces)
    for (int k = 0; k < 3; ++k) ++directed[{f[static_cast<size_t>(k)], f[static_cast<size_t>((k + 1) % 3)]}];
  for (const auto& [e, n] : directed) {
    EXPECT_EQ(n, 1);
    EXPECT_EQ(directed.count({e.second, e.first}), 1u);
  }
}

TEST(AssimpReader, ColladaCoordinatesAreTheFilesWhateverItsUpAxis) {
  TempDir dir;
  auto dae = [](const std::string& up) {
    return "<?xml version=\"1.0\" encoding=\"utf-8\"?>\n"
           "<COLLADA xmlns=\"http://www.collada.org/2005/11/COLLADASchema\" version=\"1.4.1\">\n"
           "<asset><unit name=\"meter\" meter=\"1\"/><up_axis>" + up + "</up_axis></asset>\n"
           "<library_geometries><geometry id=\"g\" name=\"tri\"><mesh>\n"
           "<source id=\"p\"><float_array id=\"pa\" count=\"9\">1 1 0.5 2 1 0.5 1 3 0.5</float_array>\n"
           "<technique_common><accessor source=\"#pa\" count=\"3\" stride=\"3\">"
           "<param name=\"X\" type=\"float\"/><param name=\"Y\" type=\"float\"/><param name=\"Z\" type=\"float\"/>"
           "</accessor></technique_common></source>\n"
           "<vertices id=\"v\"><input semantic=\"POSITION\" source=\"#p\"/></vertices>\n"
           "<triangles count=\"1\"><input semantic=\"VERTEX\" source=\"#v\" offset=\"0\"/><p>0 1 2</p></triangles>\n"
           "</mesh></geometry></library_geometries>\n"
           "<library_visual_scenes><visual_scene id=\"s\"><node id=\"n\" name=\"n\">"
           "<instance_geometry url=\"#g\"/></node></visual_scene></library_visual_scenes>\n"
           "<scene><instance_visual_scene url=\"#s\"/></scene>\n"
           "</COLLADA>\n";
  };
  for (const std::string up : {"Z_UP", "Y_UP", "X_UP"}) {
    SCOPED_TRACE(up);
    const auto groups = read_mesh_file(dir.write("tri_" + up + ".dae", dae(up)));
    ASSERT_EQ(groups.size(), 1u);
    ASSERT_EQ(groups[0].positions.size(), 3u);
    EXPECT_EQ(groups[0].positions[0], Vec3(1, 1, 0.5));
    EXPECT_EQ(groups[0].positions[2], Vec3(1, 3, 0.5));
  }
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
