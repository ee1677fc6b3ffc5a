// The OFF reader: header variants, comments and line endings, ignored extras, exact
// coordinates, and every error case (which must be an InputError, never an abort or a huge
// allocation).
#include "io/mesh_reader.hpp"
#include "io/mesh_reader_detail.hpp"
#include "io/off_reader.hpp"
#include "io/read_util.hpp"
#include "io_test_util.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace vproxq {
namespace {

using io_detail::read_off;
using test::TempDir;

std::vector<Face> faces(std::initializer_list<Face> f) { return f; }

const std::vector<Vec3> kCubeVertices = {{0, 0, 0}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0},
                                         {0, 0, 1}, {1, 0, 1}, {1, 1, 1}, {0, 1, 1}};

const char* const kCube =
    "OFF\n"
    "8 6 12\n"
    "0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
    "0 0 1\n1 0 1\n1 1 1\n0 1 1\n"
    "4 0 3 2 1\n"
    "4 4 5 6 7\n"
    "4 0 1 5 4\n"
    "4 1 2 6 5\n"
    "4 2 3 7 6\n"
    "4 3 0 4 7\n";

const std::vector<Face> kCubeTriangles = {{0, 3, 2}, {0, 2, 1}, {4, 5, 6}, {4, 6, 7},
                                          {0, 1, 5}, {0, 5, 4}, {1, 2, 6}, {1, 6, 5},
                                          {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};

/// A triangle in the file format `keyword` with `vertex_extras` after each vertex's x y z.
std::string triangle_with(const std::string& keyword, const std::string& vertex_extras) {
  return keyword + "\n3 1 0\n0 0 0" + vertex_extras + "\n1 0 0" + vertex_extras + "\n0 1 0" +
         vertex_extras + "\n3 0 1 2\n";
}

TEST(OffReader, CubeOfQuadsIsFanTriangulatedWithTheFileIndices) {
  TempDir dir;
  const auto file = dir.write("cube.off", kCube);
  const MeshGroup g = read_off(file);
  EXPECT_EQ(g.name, "cube");
  EXPECT_EQ(g.positions, kCubeVertices);
  EXPECT_EQ(g.faces, kCubeTriangles);

  // read_mesh_file and the merged variant route .off (any case) to this reader.
  const auto groups = read_mesh_file(file);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].name, "cube");
  EXPECT_EQ(groups[0].positions, kCubeVertices);
  EXPECT_EQ(groups[0].faces, kCubeTriangles);
  const MeshGroup merged = io_detail::read_mesh_file_merged(file);
  EXPECT_EQ(merged.positions, kCubeVertices);
  EXPECT_EQ(merged.faces, kCubeTriangles);
  const auto upper = dir.write("CUBE.OFF", kCube);
  EXPECT_EQ(read_mesh_file(upper)[0].faces, kCubeTriangles);
}

TEST(OffReader, PentagonAndDegenerateFacesKeptInFileOrder) {
  TempDir dir;
  const auto file = dir.write("poly.off",
                              "OFF\n6 3 0\n0 0 0\n1 0 0\n2 1 0\n1 2 0\n0 1 0\n5 5 5\n"
                              "5 4 3 2 1 0\n3 5 5 5\n3 0 1 5\n");
  const MeshGroup g = read_off(file);
  EXPECT_EQ(g.positions.size(), 6u);
  EXPECT_EQ(g.faces, faces({{4, 3, 2}, {4, 2, 1}, {4, 1, 0}, {5, 5, 5}, {0, 1, 5}}));
}

TEST(OffReader, CommentsBlankLinesAndCrlf) {
  TempDir dir;
  const auto file = dir.write("commented.off",
                              "# written by hand\r\n"
                              "\r\n"
                              "OFF # the keyword\r\n"
                              "   # counts next\r\n"
                              "3 1 0\r\n"
                              "\r\n"
                              "0 0 0 # first\r\n"
                              "#1 1 1\r\n"
                              "1 0 0\r\n"
                              "\t\r\n"
                              "0 1 0\r\n"
                              "# faces\r\n"
                              "3 0 1 2 # the only face\r\n"
                              "# the end\r\n"
                              "\r\n");
  const MeshGroup g = read_off(file);
  EXPECT_EQ(g.name, "commented");
  EXPECT_EQ(g.positions, (std::vector<Vec3>{{0, 0, 0}, {1, 0, 0}, {0, 1, 0}}));
  EXPECT_EQ(g.faces, faces({{0, 1, 2}}));

  // No newline at the end of the file.
  const auto unterminated =
      dir.write("unterminated.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2");
  EXPECT_EQ(read_off(unterminated).faces, faces({{0, 1, 2}}));
}

TEST(OffReader, ByteOrderMarkAndClassicMacLineEndings) {
  TempDir dir;
  for (const std::string& text : {std::string("\xEF\xBB\xBFOFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n"),
                                  std::string("OFF\r# c\r3 1 0\r0 0 0\r1 0 0\r0 1 0\r3 0 1 2\r")}) {
    const auto groups = read_mesh_file(dir.write("t.off", text));
    ASSERT_EQ(groups.size(), 1u);
    EXPECT_EQ(groups[0].positions[1], Vec3(1, 0, 0));
    EXPECT_EQ(groups[0].faces, (std::vector<Face>{{0, 1, 2}}));
  }
}

TEST(OffReader, CountsOnTheKeywordLineOrWithoutKeyword) {
  TempDir dir;
  // After the keyword the edge count may be left out.
  const auto two = dir.write("two.off", "OFF\n3 1\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_EQ(read_off(two).faces, faces({{0, 1, 2}}));
  // Data past the declared faces: the counts do not describe the file.
  const auto more = dir.write("more.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 2 1 0\n# end\n");
  EXPECT_INPUT_ERROR(read_off(more), more.string() + ": line 7: '3 2 1 0' after the 1 faces");
  const auto same_line =
      dir.write("same_line.off", "OFF 4 2 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n3 0 2 3\n");
  const MeshGroup a = read_off(same_line);
  EXPECT_EQ(a.positions.size(), 4u);
  EXPECT_EQ(a.faces, faces({{0, 1, 2}, {0, 2, 3}}));

  const auto no_keyword =
      dir.write("no_keyword.off", "# no keyword\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
  const MeshGroup b = read_off(no_keyword);
  EXPECT_EQ(b.positions.size(), 4u);
  EXPECT_EQ(b.faces, faces({{0, 1, 2}, {0, 2, 3}}));

  const auto no_faces = dir.write("points.off", "OFF\n2 0 0\n0 0 0\n1 1 1\n");
  const MeshGroup c = read_off(no_faces);
  EXPECT_EQ(c.positions.size(), 2u);
  EXPECT_TRUE(c.faces.empty());
}

TEST(OffReader, VertexExtrasAndFaceColoursAreIgnored) {
  TempDir dir;
  const std::vector<Vec3> expected = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
  const struct {
    const char* keyword;
    const char* extras;
  } variants[] = {{"OFF", ""},
                  {"COFF", " 255 0 0 255"},
                  {"COFF", " 0.5 0.25 1 1"},
                  {"NOFF", " 0 0 1"},
                  {"CNOFF", " 0 0 1 0.1 0.2 0.3 1"},
                  {"STOFF", " 0.5 0.5"},
                  {"STCNOFF", " 0 0 1 1 0 0 1 0.5 0.5"}};
  for (const auto& v : variants) {
    SCOPED_TRACE(std::string(v.keyword) + v.extras);
    const auto file = dir.write("tri.off", triangle_with(v.keyword, v.extras));
    const MeshGroup g = read_off(file);
    EXPECT_EQ(g.positions, expected);
    EXPECT_EQ(g.faces, faces({{0, 1, 2}}));
  }
  // Face colours: a colour map index, or RGB / RGBA as integers or floats.
  const auto coloured = dir.write("coloured.off",
                                  "OFF\n4 3 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
                                  "3 0 1 2 7\n3 0 2 3 255 0 0\n4 0 1 2 3 0.1 0.2 0.3 0.75\n");
  EXPECT_EQ(read_off(coloured).faces, faces({{0, 1, 2}, {0, 2, 3}, {0, 1, 2}, {0, 2, 3}}));
}

TEST(OffReader, CoordinatesAreParsedExactlyAsDoubles) {
  TempDir dir;
  const char* const tokens[] = {"0.1",     "-0.2",
                                "+0.3",    "1e59",
                                "6.3e-61", "3.141592653589793",
                                "-0",      "1E-3",
                                "2.5",     "0.30000000000000004",
                                "-1e-60",  "123456789.123456789"};
  std::string text = "OFF\n4 1 0\n";
  for (int v = 0; v < 4; ++v) {
    text += std::string(tokens[3 * v]) + " " + tokens[3 * v + 1] + " " + tokens[3 * v + 2] + "\n";
  }
  text += "3 0 1 2\n";
  const auto file = dir.write("exact.off", text);
  const MeshGroup g = read_off(file);
  ASSERT_EQ(g.positions.size(), 4u);
  for (int v = 0; v < 4; ++v) {
    for (int a = 0; a < 3; ++a) {
      double expected = 0;
      ASSERT_TRUE(io_detail::parse_double(tokens[3 * v + a], expected));
      EXPECT_EQ(g.positions[static_cast<std::size_t>(v)][a], expected) << tokens[3 * v + a];
    }
  }
  EXPECT_EQ(g.positions[0].x(), 0.1);
  EXPECT_EQ(g.positions[0].y(), -0.2);
  EXPECT_EQ(g.positions[3].z(), 123456789.123456789);
}

// ---- errors -------------------------------------------------------------------------------

TEST(OffReaderErrors, MissingFileAndDirectory) {
  TempDir dir;
  const auto missing = dir.path() / "nothing.off";
  EXPECT_INPUT_ERROR(read_off(missing), missing.string() + ": file not found");
  EXPECT_INPUT_ERROR(read_mesh_file(missing), missing.string() + ": file not found");
  const auto folder = dir.path() / "folder.off";
  std::filesystem::create_directories(folder);
  EXPECT_INPUT_ERROR(read_off(folder), folder.string() + ": is not a regular file");
}

TEST(OffReaderErrors, MalformedHeaders) {
  TempDir dir;
  const struct {
    const char* text;
    const char* expect;
  } cases[] = {
      {"", ": not an OFF file (it holds no data)"},
      {"# only a comment\n\n", ": not an OFF file (it holds no data)"},
      {"ply\nformat ascii 1.0\n", ": line 1: not an OFF file (expected 'OFF' or the counts"},
      {"off\n3 1 0\n", ": line 1: not an OFF file"},
      {"3 1\n0 0 0\n", ": line 1: not an OFF file"},
      {"XOFF\n3 1 0\n", ": line 1: unknown OFF keyword 'XOFF'"},
      {"OFF BINARY\n", ": line 1: binary OFF ('OFF BINARY') is not supported"},
      {"COFF BINARY\n", ": line 1: binary OFF ('COFF BINARY') is not supported"},
      {"4OFF\n3 1 0\n", ": line 1: '4OFF' (4D vertices) is not supported"},
      {"nOFF\n3\n3 1 0\n", ": line 1: 'nOFF' (n-dimensional vertices) is not supported"},
      {"OFF\n", "malformed OFF header: the file ends before the counts line"},
      {"OFF\n# counts missing\n", "malformed OFF header: the file ends before the counts line"},
      {"OFF\n3\n",
       ": line 2: malformed OFF header: expected the counts 'vertices faces edges', got 1 values"},
      {"OFF 3 1 0 0\n", ": line 1: malformed OFF header: expected the counts"},
      {"OFF\n-3 1 0\n",
       ": line 2: malformed OFF header: the vertex count '-3' is not a non-negative integer"},
      {"OFF\n3 x 0\n",
       ": line 2: malformed OFF header: the face count 'x' is not a non-negative integer"},
      {"OFF\n3 1.0 0\n", "the face count '1.0' is not a non-negative integer"},
      {"OFF\n3 1 -1\n", "the edge count '-1' is not a non-negative integer"},
      {"OFF\n99999999999999999999 1 0\n",
       "the vertex count '99999999999999999999' is not a non-negative integer"},
      {"OFF\n3000000000 0 0\n",
       ": line 2: too many vertices (3000000000), at most 2147483647 are supported"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.text);
    const auto file = dir.write("bad.off", c.text);
    EXPECT_INPUT_ERROR(read_off(file), file.string() + ":", c.expect);
  }
}

TEST(OffReaderErrors, CountsLargerThanTheFileHolds) {
  TempDir dir;
  // The header says 2 faces, the file holds 1 (assimp aborted the process on this one).
  const auto short_faces =
      dir.write("short.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n");
  EXPECT_INPUT_ERROR(read_off(short_faces),
                     short_faces.string() +
                         ": line 2: the header declares 2 faces, but the file has only 1 line "
                         "of data after the 4 vertex lines");
  const auto short_vertices = dir.write("short_vertices.off", "OFF 4 0 0\n0 0 0\n1 0 0\n");
  EXPECT_INPUT_ERROR(read_off(short_vertices),
                     short_vertices.string() +
                         ": line 1: the header declares 4 vertices, but the file has only 2 "
                         "lines of data after the header");
  // Comments and blank lines are not data lines.
  const auto comments = dir.write("comments.off", "OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n# 3 0 1 2\n\n");
  EXPECT_INPUT_ERROR(
      read_off(comments),
      comments.string() + ": line 2: the header declares 1 face, but the file has only 0 lines");
  // Records split over several lines count as more lines but then do not parse.
  const auto split = dir.write("split.off", "OFF\n1 0 0\n0 0\n0\n");
  EXPECT_INPUT_ERROR(
      read_off(split),
      split.string() + ": line 3: vertex 0 (0-based): expected 3 coordinates, got 2");
}

TEST(OffReaderErrors, HugeCountsInATinyFileFailAtOnce) {
  // A 60-byte file claiming 1e9 vertices and faces: rejected from the line count, before any
  // allocation (assimp spent ~80 s and all memory on it).
  TempDir dir;
  const auto file =
      dir.write("huge-count.off", "OFF\n1000000000 1000000000 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  EXPECT_INPUT_ERROR(read_off(file), file.string() +
                                         ": line 2: the header declares 1000000000 vertices, but "
                                         "the file has only 4 lines of data after the header");
  const auto faces_only = dir.write("huge-faces.off", "OFF 3 2000000000 0\n0 0 0\n1 0 0\n0 1 0\n");
  EXPECT_INPUT_ERROR(read_off(faces_only), faces_only.string() +
                                               ": line 1: the header declares 2000000000 faces, "
                                               "but the file has only 0 lines of data after the "
                                               "3 vertex lines");
}

TEST(OffReaderErrors, MalformedVertices) {
  TempDir dir;
  const struct {
    const char* vertex;  // the second vertex line
    const char* expect;
  } cases[] = {
      {"1 0", ": line 4: vertex 1 (0-based): expected 3 coordinates, got 2"},
      {"1 0 zero", ": line 4: vertex 1 (0-based): 'zero' is not a number"},
      {"1 0 0 red", ": line 4: vertex 1 (0-based): 'red' is not a number"},
      {"1,0,0", ": line 4: vertex 1 (0-based): '1,0,0' is not a number"},
      {"1 0 nan", ": line 4: vertex 1 (0-based) has a non-finite coordinate (z = nan)"},
      {"-inf 0 0", ": line 4: vertex 1 (0-based) has a non-finite coordinate (x = -inf)"},
      {"1 1e400 0", ": line 4: vertex 1 (0-based) has a non-finite coordinate (y = inf)"},
      {"1 0 1e61", ": line 4: vertex 1 (0-based) has a coordinate out of range (z = 1e+61"},
      {"1e-70 0 0", ": line 4: vertex 1 (0-based) has a coordinate too close to 0 (x = 1e-70"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.vertex);
    const auto file = dir.write(
        "vertex.off", std::string("OFF\n3 1 0\n0 0 0\n") + c.vertex + "\n0 1 0\n3 0 1 2\n");
    EXPECT_INPUT_ERROR(read_off(file), file.string() + c.expect);
  }
}

TEST(OffReaderErrors, MalformedFaces) {
  TempDir dir;
  const struct {
    const char* face;  // the second face line
    const char* expect;
  } cases[] = {
      {"2 0 1", ": line 7: face 1 (0-based) has 2 vertices (a face needs at least 3)"},
      {"0", ": line 7: face 1 (0-based) has 0 vertices (a face needs at least 3)"},
      {"-3 0 1 2", ": line 7: face 1 (0-based) has -3 vertices (a face needs at least 3)"},
      {"4 0 1 2", ": line 7: face 1 (0-based): expected 4 vertex indices, got 3"},
      {"1000000000000 0 1 2",
       ": line 7: face 1 (0-based): expected 1000000000000 vertex indices, got 3"},
      {"3.0 0 1 2", ": line 7: face 1 (0-based): the vertex count '3.0' is not an integer"},
      {"three 0 1 2", ": line 7: face 1 (0-based): the vertex count 'three' is not an integer"},
      {"3 0 1 2.0", ": line 7: face 1 (0-based): vertex index '2.0' is not an integer"},
      {"3 0 one 2", ": line 7: face 1 (0-based): vertex index 'one' is not an integer"},
      {"3 0 1 3", ": line 7: face 1 (0-based): vertex index 3 out of range (file has 3 vertices)"},
      {"3 0 1 7", ": line 7: face 1 (0-based): vertex index 7 out of range (file has 3 vertices)"},
      {"3 0 1 -5",
       ": line 7: face 1 (0-based): vertex index -5 out of range (file has 3 vertices)"},
      {"3 0 1 -1", ": line 7: face 1 (0-based): vertex index -1 out of range"},
      {"3 0 1 99999999999999999999",
       ": line 7: face 1 (0-based): vertex index '99999999999999999999' is not an integer"},
      {"3 0 1 2 red",
       ": line 7: face 1 (0-based): 'red' after the 3 vertex indices is not a number"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.face);
    const auto file = dir.write(
        "face.off", std::string("OFF\n3 2 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n") + c.face + "\n");
    EXPECT_INPUT_ERROR(read_off(file), file.string() + c.expect);
    // The same through read_mesh_file: the error is not lost or replaced on the way.
    EXPECT_INPUT_ERROR(read_mesh_file(file), file.string() + c.expect);
  }
}

}  // namespace
}  // namespace vproxq
