// The OBJ reader: the file's own indices, double precision, groups, and every error case.
#include "io/mesh_reader.hpp"
#include "io/obj_reader.hpp"
#include "io_test_util.hpp"

#include <gtest/gtest.h>

#include <cstdlib>
#include <fstream>
#include <sstream>

namespace vproxq {
namespace {

using test::TempDir;

std::vector<Face> faces(std::initializer_list<Face> f) { return f; }

TEST(ObjReader, SlashFormsQuadsAndWeightsKeepFileIndices) {
  TempDir dir;
  const auto file = dir.write("shape.obj",
                              "# a comment\n"
                              "mtllib shape.mtl\n"
                              "v 0 0 0\n"
                              "v 1 0 0\n"
                              "v 1 1 0\n"
                              "v 0 1 0\n"
                              "v 0.5 0.5 1 1.0\n"      // with w
                              "v 2 2 2 0.1 0.2 0.3\n"  // with a vertex colour
                              "vt 0 0\nvt 1 0\nvt 1 1\n"
                              "vn 0 0 1\n"
                              "usemtl red\n"
                              "s off\n"
                              "f 1 2 3 4\n"  // quad: fan triangulated
                              "f 1/1 2/2 5/3\n"
                              "f 2//1 3//1 5//1\n"
                              "f 3/3/1 4/1/1 5/2/1 # trailing comment\n");
  const std::vector<MeshGroup> groups = read_mesh_file(file);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].name, "shape");
  ASSERT_EQ(groups[0].positions.size(), 6u);  // the unused sixth vertex is kept
  EXPECT_EQ(groups[0].positions[4], Vec3(0.5, 0.5, 1));
  EXPECT_EQ(groups[0].positions[5], Vec3(2, 2, 2));
  EXPECT_EQ(groups[0].faces, faces({{0, 1, 2}, {0, 2, 3}, {0, 1, 4}, {1, 2, 4}, {2, 3, 4}}));
}

TEST(ObjReader, NegativeIndicesAreRelativeToVerticesReadSoFar) {
  TempDir dir;
  const auto file = dir.write("rel.obj",
                              "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
                              "f -3 -2 -1\n"
                              "v 0 0 1\n"
                              "f -4/-1 -1/-2 -2//-1\n"
                              "f 1 -1 3\n");
  const auto groups = read_mesh_file(file);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].faces, faces({{0, 1, 2}, {0, 3, 2}, {0, 3, 2}}));
}

TEST(ObjReader, PolygonsAreFanTriangulated) {
  TempDir dir;
  const auto file = dir.write("poly.obj",
                              "v 0 0 0\nv 1 0 0\nv 2 1 0\nv 1 2 0\nv 0 1 0\n"
                              "f 1 2 3 4 5\n");
  EXPECT_EQ(read_mesh_file(file)[0].faces, faces({{0, 1, 2}, {0, 2, 3}, {0, 3, 4}}));
}

TEST(ObjReader, PositiveIndicesMayReferToLaterVertices) {
  TempDir dir;
  const auto file = dir.write("fwd.obj", "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
  const auto groups = read_mesh_file(file);
  EXPECT_EQ(groups[0].faces, faces({{0, 1, 2}}));
  EXPECT_EQ(groups[0].positions.size(), 3u);
}

TEST(ObjReader, CoordinatesAreParsedAsDoubles) {
  TempDir dir;
  const char* xs[] = {"0.1", "-1.2345678901234567e-60", "123456789.123456789", "+2.5", "1E+10",
                      "3"};
  std::string text;
  for (int i = 0; i < 6; i += 3) {
    text += std::string("v ") + xs[i] + " " + xs[i + 1] + " " + xs[i + 2] + "\n";
  }
  const auto file = dir.write("precise.obj", text);
  const auto groups = read_mesh_file(file);
  ASSERT_EQ(groups[0].positions.size(), 2u);
  for (int i = 0; i < 6; ++i) {
    EXPECT_EQ(groups[0].positions[static_cast<std::size_t>(i / 3)][i % 3],
              std::strtod(xs[i], nullptr))
        << xs[i];
  }
}

TEST(ObjReader, ByteOrderMarkAndClassicMacLineEndings) {
  TempDir dir;
  for (const std::string& text : {std::string("\xEF\xBB\xBF# made by X\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"),
                                  std::string("# made by X\rv 0 0 0\rv 1 0 0\r\rv 0 1 0\rf 1 2 3\r")}) {
    const auto groups = read_mesh_file(dir.write("t.obj", text));
    ASSERT_EQ(groups.size(), 1u);
    EXPECT_EQ(groups[0].positions[1], Vec3(1, 0, 0));
    EXPECT_EQ(groups[0].faces, faces({{0, 1, 2}}));
  }
}

TEST(ObjReader, CrlfTabsAndBlankLines) {
  TempDir dir;
  const auto file = dir.write("crlf.obj", "v\t0 0 0\r\n\r\n  v 1 0 0\r\nv 0 1 0\r\nf\t1 2 3\r\n");
  const auto groups = read_mesh_file(file);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].positions[1], Vec3(1, 0, 0));
  EXPECT_EQ(groups[0].faces, faces({{0, 1, 2}}));
}

TEST(ObjReader, SeveralGroupsGetTheVerticesTheyUseInFileOrder) {
  TempDir dir;
  const auto file = dir.write("multi.obj",
                              "v 0 0 0\n"  // 1
                              "v 1 0 0\n"  // 2
                              "v 0 1 0\n"  // 3
                              "v 5 5 5\n"  // 4: used by no face
                              "v 2 0 0\n"  // 5
                              "v 3 0 0\n"  // 6
                              "v 2 1 0\n"  // 7
                              "o first\n"
                              "f 1 2 3\n"
                              "g empty group\n"  // no faces: dropped
                              "o second\n"
                              "f 5 6 7\n"
                              "f 7 6 2\n");
  const auto groups = read_mesh_file(file);
  ASSERT_EQ(groups.size(), 2u);
  EXPECT_EQ(groups[0].name, "first");
  EXPECT_EQ(groups[0].positions, (std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}));
  EXPECT_EQ(groups[0].faces, faces({{0, 1, 2}}));
  EXPECT_EQ(groups[1].name, "second");
  // Global vertices 2, 5, 6, 7 in that order.
  EXPECT_EQ(groups[1].positions, (std::vector<Vec3>{{1, 0, 0}, {2, 0, 0}, {3, 0, 0}, {2, 1, 0}}));
  EXPECT_EQ(groups[1].faces, faces({{1, 2, 3}, {3, 2, 0}}));
}

TEST(ObjReader, GroupsWithScatteredVerticesKeepFileOrderToo) {
  // A group's vertices are collected by marking their range where it is a few times the
  // corners, else by sorting: both give file order.
  TempDir dir;
  std::string text;
  for (int i = 1; i <= 50; ++i) text += "v " + std::to_string(i) + " 0 " + std::to_string(i % 7) + "\n";
  text += "o near\nf 10 12 11\no far\nf 50 1 25\nf 25 1 49\n";
  const auto groups = read_mesh_file(dir.write("scattered.obj", text));
  ASSERT_EQ(groups.size(), 2u);
  EXPECT_EQ(groups[0].positions, (std::vector<Vec3>{{10, 0, 3}, {11, 0, 4}, {12, 0, 5}}));
  EXPECT_EQ(groups[0].faces, faces({{0, 2, 1}}));
  EXPECT_EQ(groups[1].positions, (std::vector<Vec3>{{1, 0, 1}, {25, 0, 4}, {49, 0, 0}, {50, 0, 1}}));
  EXPECT_EQ(groups[1].faces, faces({{3, 0, 1}, {1, 0, 2}}));
}

TEST(ObjReader, UnnamedGroupsAreNamedAfterTheFileStem) {
  TempDir dir;
  const auto file = dir.write("parts.obj",
                              "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                              "f 1 2 3\n"  // before any group
                              "g\n"
                              "f 1 2 4\n"
                              "o named\n"
                              "f 1 3 4\n");
  const auto groups = read_mesh_file(file);
  ASSERT_EQ(groups.size(), 3u);
  EXPECT_EQ(groups[0].name, "parts_0");
  EXPECT_EQ(groups[1].name, "parts_1");
  EXPECT_EQ(groups[2].name, "named");
  EXPECT_EQ(groups[1].positions, (std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 0, 1}}));
  EXPECT_EQ(groups[1].faces, faces({{0, 1, 2}}));
}

// A comment after a group name is not part of it (as after v and f values): the name ends at
// a word that starts with '#'; a '#' inside a word stays in the name.
TEST(ObjReader, GroupNamesEndWhereACommentStarts) {
  TempDir dir;
  const auto file = dir.write("comments.obj",
                              "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                              "o cloth   # the skirt\n"
                              "f 1 2 3 # first\n"
                              "g part#2 left\t#note\n"
                              "f 1 2 4\n"
                              "o #only a comment\n"
                              "f 1 3 4\n");
  const auto groups = read_mesh_file(file);
  ASSERT_EQ(groups.size(), 3u);
  EXPECT_EQ(groups[0].name, "cloth");
  EXPECT_EQ(groups[1].name, "part#2 left");
  EXPECT_EQ(groups[2].name, "comments_2");  // no name left: unnamed
}

TEST(ObjReader, OneGroupWithFacesKeepsAllVerticesAndItsName) {
  TempDir dir;
  const auto file = dir.write("one.obj",
                              "o lonely\n"
                              "v 9 9 9\n"  // isolated, kept
                              "v 0 0 0\nv 1 0 0\nv 0 1 0\n"
                              "f 2 3 4\n"
                              "g nothing\n");
  const auto groups = read_mesh_file(file);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].name, "lonely");
  EXPECT_EQ(groups[0].positions.size(), 4u);
  EXPECT_EQ(groups[0].faces, faces({{1, 2, 3}}));
}

TEST(ObjReader, VerticesOnlyGiveOneGroupWithoutFaces) {
  TempDir dir;
  const auto file = dir.write("cloud.obj", "v 0 0 0\nv 1 1 1\n");
  const auto groups = read_mesh_file(file);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].name, "cloud");
  EXPECT_EQ(groups[0].positions.size(), 2u);
  EXPECT_TRUE(groups[0].faces.empty());
}

TEST(ObjReader, MergeModeKeepsEveryVertexInFileOrder) {
  TempDir dir;
  const auto file = dir.write("merge.obj",
                              "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 7 7 7\nv 2 0 0\nv 3 0 0\n"
                              "o a\nf 1 2 3\no b\nf 5 6 2\n");
  const auto groups = io_detail::read_obj(file, io_detail::ObjGroups::Merge);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].name, "merge");
  EXPECT_EQ(groups[0].positions.size(), 6u);
  EXPECT_EQ(groups[0].faces, faces({{0, 1, 2}, {4, 5, 1}}));
}

TEST(ObjReader, BunnyFromTestData) {
  const std::filesystem::path file =
      std::filesystem::path(VPROXQ_TEST_DATA_DIR) / "meshes/bunny-npm.obj";
  std::ifstream in(file);
  std::string line;
  std::size_t v = 0, f = 0;
  while (std::getline(in, line)) {
    if (line.rfind("v ", 0) == 0) ++v;
    if (line.rfind("f ", 0) == 0) ++f;
  }
  const auto groups = read_mesh_file(file);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].name, "bunny");
  EXPECT_EQ(v, 1839u);
  EXPECT_EQ(groups[0].positions.size(), v);
  EXPECT_EQ(groups[0].faces.size(), f);  // all triangles
  EXPECT_EQ(groups[0].positions[0], Vec3(1.301895, 0.122622, 2.550061));
}

// ---- errors: the message starts with the file and says what is wrong ----

TEST(ObjReaderErrors, MissingFile) {
  TempDir dir;
  const auto file = dir.path() / "nope.obj";
  EXPECT_INPUT_ERROR(read_mesh_file(file), file.string() + ": file not found");
}

TEST(ObjReaderErrors, FaceIndexOutOfRange) {
  TempDir dir;
  const auto file = dir.write("a_0003.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 812\n");
  EXPECT_INPUT_ERROR(read_mesh_file(file),
                     file.string() + ": line 5: face index 812 out of range (file has 3 vertices)");
  // Indices past the vertices read so far are checked once the file's count is known: the
  // first line with one past the count is named, not a valid forward reference before it.
  const auto fwd = dir.write("fwd.obj", "f 1 2 3\nf 3 2 1\nf 1 4 9\nf 1 2 7\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n");
  EXPECT_INPUT_ERROR(read_mesh_file(fwd),
                     fwd.string() + ": line 3: face index 9 out of range (file has 4 vertices)");
  const auto huge = dir.write("huge.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 99999999999\n");
  EXPECT_INPUT_ERROR(read_mesh_file(huge),
                     huge.string() + ": line 4: face index 99999999999 out of range (file has 3 vertices)");
}

TEST(ObjReaderErrors, ZeroFaceIndex) {
  TempDir dir;
  const auto file = dir.write("zero.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 0 1 2\n");
  EXPECT_INPUT_ERROR(read_mesh_file(file), file.string() + ": line 4:", "face index 0");
}

TEST(ObjReaderErrors, RelativeIndexBeforeTheFirstVertex) {
  TempDir dir;
  const auto file = dir.write("rel.obj", "v 0 0 0\nv 1 0 0\nf -1 -2 -3\nv 0 1 0\n");
  EXPECT_INPUT_ERROR(read_mesh_file(file),
                     file.string() + ": line 3:", "face index -3 out of range");
}

TEST(ObjReaderErrors, FaceWithTwoVertices) {
  TempDir dir;
  const auto file = dir.write("two.obj", "v 0 0 0\nv 1 0 0\nf 1 2\n");
  EXPECT_INPUT_ERROR(read_mesh_file(file), file.string() + ": line 3:", "face with 2 vertices");
}

TEST(ObjReaderErrors, MalformedVertex) {
  TempDir dir;
  const auto a = dir.write("a.obj", "v 0 zero 0\n");
  EXPECT_INPUT_ERROR(read_mesh_file(a), a.string() + ": line 1:", "'zero' is not a number");
  const auto b = dir.write("b.obj", "v 0 0\n");
  EXPECT_INPUT_ERROR(read_mesh_file(b), b.string() + ": line 1:", "expected 3 coordinates");
}

TEST(ObjReaderErrors, NonFiniteCoordinateNamesTheVertex) {
  TempDir dir;
  const auto a = dir.write("nan.obj", "v 0 0 0\nv 1 nan 0\n");
  EXPECT_INPUT_ERROR(read_mesh_file(a), a.string() + ": line 2:", "vertex 2", "non-finite",
                     "y = nan");
  const auto b = dir.write("inf.obj", "v 0 0 0\nv 1 0 0\nv 0 1 -inf\n");
  EXPECT_INPUT_ERROR(read_mesh_file(b), b.string() + ": line 3:", "vertex 3", "z = -inf");
  const auto c = dir.write("huge.obj", "v 1e999 0 0\n");
  EXPECT_INPUT_ERROR(read_mesh_file(c), c.string() + ": line 1:", "vertex 1", "non-finite");
}

// Coordinates at or past 2^200 in magnitude, or nonzero below 2^-200 (outside the range where
// the exact predicates are exact and squared distances finite) are input errors; the rest is
// read.
TEST(ObjReaderErrors, CoordinateOutOfRangeNamesTheVertex) {
  TempDir dir;
  const auto a = dir.write("far.obj", "v 0 0 0\nv 1 0 0\nv 0 1 -1e61\n");
  EXPECT_INPUT_ERROR(read_mesh_file(a), a.string() + ": line 3:", "vertex 3", "out of range",
                     "z = -1e+61;", "2^200");
  const auto b = dir.write("edge.obj", "v 1606938044258990275541962092341162602522202993782792835301376 0 0\n");
  EXPECT_INPUT_ERROR(read_mesh_file(b), b.string() + ": line 1:", "x = 1.6069380442589903e+60;", "out of range");
  const auto d = dir.write("tiny.obj", "v 0 0 0\nv 1 -1e-61 0\n");
  EXPECT_INPUT_ERROR(read_mesh_file(d), d.string() + ": line 2:", "vertex 2", "too close to 0",
                     "y = -1e-61;", "write 0");
  // Below double's range: too close to 0 as well, not "non-finite" and not read as 0.
  const auto e = dir.write("under.obj", "v 0 0 0\nv 1 -1e-400 0\n");
  EXPECT_INPUT_ERROR(read_mesh_file(e), e.string() + ": line 2:", "vertex 2", "too close to 0", "y = -5e-324;");
  const auto f = dir.write("over.obj", "v 0 0 0\nv 1 -1e400 0\n");
  EXPECT_INPUT_ERROR(read_mesh_file(f), f.string() + ": line 2:", "vertex 2", "non-finite", "y = -inf");
  const auto c = dir.write("ok.obj", "v 1e60 -1e60 0\nv 1 6.3e-61 -0\nv 0 1 0\nf 1 2 3\n");
  const auto groups = read_mesh_file(c);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].positions[0], Vec3(1e60, -1e60, 0));
  EXPECT_EQ(groups[0].positions[1], Vec3(1, 6.3e-61, 0));
}

TEST(ObjReaderErrors, MalformedFaceCorners) {
  TempDir dir;
  const auto a = dir.write("a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/1/1/1 2 3\n");
  EXPECT_INPUT_ERROR(read_mesh_file(a), a.string() + ": line 4:", "malformed face corner");
  const auto b = dir.write("b.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf x 2 3\n");
  EXPECT_INPUT_ERROR(read_mesh_file(b), b.string() + ": line 4:", "'x' is not an integer");
  const auto c = dir.write("c.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1/a 2 3\n");
  EXPECT_INPUT_ERROR(read_mesh_file(c), c.string() + ": line 4:", "malformed face corner");
  const auto d = dir.write("d.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1.5 2 3\n");
  EXPECT_INPUT_ERROR(read_mesh_file(d), d.string() + ": line 4:", "not an integer");
}

TEST(ObjReaderErrors, UnknownStatementAndLineContinuation) {
  TempDir dir;
  // Control bytes (a binary file, an escape sequence) are shown escaped, never raw.
  const auto bin = dir.write("bin.obj", std::string("\x01\x1b[31mred\x7f 1 2\n"));
  EXPECT_INPUT_ERROR(read_mesh_file(bin), bin.string() + ": line 1:", "unknown statement '\\x01\\x1b[31mred\\x7f'");
  try {
    read_mesh_file(bin);
  } catch (const InputError& e) {
    EXPECT_EQ(std::string(e.what()).find('\x1b'), std::string::npos) << e.what();
  }
  const auto a = dir.write("a.obj", "v 0 0 0\nvertex 1 2 3\n");
  EXPECT_INPUT_ERROR(read_mesh_file(a), a.string() + ": line 2:", "unknown statement 'vertex'");
  const auto b = dir.write("b.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 \\\n 3\n");
  EXPECT_INPUT_ERROR(read_mesh_file(b), b.string() + ": line 4:", "line continuation");
}

}  // namespace
}  // namespace vproxq
