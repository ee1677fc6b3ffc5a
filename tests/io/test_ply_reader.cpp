// The PLY reader: ascii and both binary byte orders, any scalar types, skipped properties
// and elements, and every error case.
#include "io/mesh_reader.hpp"
#include "io_test_util.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <limits>

namespace vproxq {
namespace {

using test::put;
using test::TempDir;

std::vector<Face> faces(std::initializer_list<Face> f) { return f; }

/// A square (4 vertices) as one quad plus one triangle.
const std::vector<Vec3> kSquare = {
    {0.1, 0.2, 0.3}, {1.0 / 3.0, 0.0, -0.0}, {1e-60, 1e59, 2.5}, {-7.25, 4.0, 1.0 / 7.0}};

TEST(PlyReader, AsciiWithExtraPropertiesAndElements) {
  TempDir dir;
  const auto file = dir.write("square.ply",
                              "ply\n"
                              "format ascii 1.0\n"
                              "comment made by hand\n"
                              "obj_info nothing\n"
                              "element vertex 4\n"
                              "property float x\n"
                              "property uchar red\n"
                              "property float y\n"
                              "property float z\n"
                              "property list uchar float weights\n"
                              "element face 2\n"
                              "property uchar flags\n"
                              "property list uchar int vertex_indices\n"
                              "property list uchar int other\n"
                              "element edge 1\n"
                              "property int vertex1\n"
                              "property int vertex2\n"
                              "end_header\n"
                              "0.1 255 0.2 0.3 2 0.5 0.5\n"
                              "1 0 0 0 0\n"
                              "1 0 1 0 1 7\n"
                              "0 0 1 0 0\n"
                              "9 4 0 1 2 3 0\n"
                              "\n"  // blank lines between records are fine
                              "9 3 3 2 1 1 42\n"
                              "0 1\n");
  const auto groups = read_mesh_file(file);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].name, "square");
  // ascii values are parsed as doubles whatever their declared type
  EXPECT_EQ(groups[0].positions,
            (std::vector<Vec3>{{0.1, 0.2, 0.3}, {1, 0, 0}, {1, 1, 0}, {0, 1, 0}}));
  EXPECT_EQ(groups[0].faces, faces({{0, 1, 2}, {0, 2, 3}, {3, 2, 1}}));
}

TEST(PlyReader, AsciiCrlfHeaderAndVertexIndexName) {
  TempDir dir;
  const auto file = dir.write("crlf.ply",
                              "ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty double x\r\n"
                              "property double y\r\nproperty double z\r\nelement face 1\r\n"
                              "property list uint8 uint32 vertex_index\r\nend_header\r\n"
                              "0 0 0\r\n1 0 0\r\n0 1 0\r\n3 0 1 2\r\n");
  const auto groups = read_mesh_file(file);
  EXPECT_EQ(groups[0].positions.size(), 3u);
  EXPECT_EQ(groups[0].faces, faces({{0, 1, 2}}));
}

TEST(PlyReader, ByteOrderMark) {
  TempDir dir;
  const auto file = dir.write("bom.ply",
                              "\xEF\xBB\xBFply\nformat ascii 1.0\nelement vertex 3\nproperty double x\n"
                              "property double y\nproperty double z\nelement face 1\n"
                              "property list uint8 uint32 vertex_indices\nend_header\n"
                              "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n");
  const auto groups = read_mesh_file(file);
  EXPECT_EQ(groups[0].positions.size(), 3u);
  EXPECT_EQ(groups[0].faces, faces({{0, 1, 2}}));
}

/// A binary PLY of kSquare (quad + triangle) with coordinates of type T.
template <class T>
std::string binary_square(bool big_endian, const char* type_name) {
  std::string s = std::string("ply\nformat ") +
                  (big_endian ? "binary_big_endian" : "binary_little_endian") +
                  " 1.0\n"
                  "element vertex 4\n"
                  "property " +
                  type_name + " x\nproperty " + type_name +
                  " y\n"
                  "property " +
                  type_name +
                  " z\n"
                  "element face 2\n"
                  "property list uchar int vertex_indices\n"
                  "end_header\n";
  for (const Vec3& p : kSquare) {
    for (int a = 0; a < 3; ++a) put<T>(s, static_cast<T>(p[a]), big_endian);
  }
  put<std::uint8_t>(s, 4, big_endian);
  for (int i : {0, 1, 2, 3}) put<std::int32_t>(s, i, big_endian);
  put<std::uint8_t>(s, 3, big_endian);
  for (int i : {3, 2, 1}) put<std::int32_t>(s, i, big_endian);
  return s;
}

TEST(PlyReader, BinaryLittleEndianDoublesStayExact) {
  TempDir dir;
  const auto file = dir.write("le.ply", binary_square<double>(false, "double"));
  const auto groups = read_mesh_file(file);
  ASSERT_EQ(groups.size(), 1u);
  EXPECT_EQ(groups[0].positions, kSquare);
  EXPECT_EQ(groups[0].faces, faces({{0, 1, 2}, {0, 2, 3}, {3, 2, 1}}));
}

TEST(PlyReader, BinaryBigEndianDoublesStayExact) {
  TempDir dir;
  const auto file = dir.write("be.ply", binary_square<double>(true, "float64"));
  const auto groups = read_mesh_file(file);
  EXPECT_EQ(groups[0].positions, kSquare);
  EXPECT_EQ(groups[0].faces, faces({{0, 1, 2}, {0, 2, 3}, {3, 2, 1}}));
}

TEST(PlyReader, BinaryFloatsBothByteOrders) {
  TempDir dir;
  // float -> double is exact, so the values come back as the floats written.
  for (bool big : {false, true}) {
    std::string s = std::string("ply\nformat ") +
                    (big ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                    "element face 0\nproperty list uchar int vertex_indices\nend_header\n";
    for (float v : {0.1f, -2.5f, 1e-30f, 3.0e30f, 1.0f / 3.0f, 0.0f}) put<float>(s, v, big);
    const auto file = dir.write(big ? "be.ply" : "le.ply", s);
    const auto groups = read_mesh_file(file);
    ASSERT_EQ(groups[0].positions.size(), 2u);
    EXPECT_EQ(groups[0].positions[0], Vec3(0.1f, -2.5f, 1e-30f));
    EXPECT_EQ(groups[0].positions[1], Vec3(3.0e30f, 1.0f / 3.0f, 0.0f));
    EXPECT_TRUE(groups[0].faces.empty());
  }
}

TEST(PlyReader, BinaryIntegerCoordinatesSkippedElementsAndListsInVertex) {
  TempDir dir;
  for (bool big : {false, true}) {
    std::string s = std::string("ply\nformat ") +
                    (big ? "binary_big_endian" : "binary_little_endian") +
                    " 1.0\n"
                    "element material 2\n"
                    "property list ushort char name\n"
                    "property double shininess\n"
                    "element vertex 3\n"
                    "property short x\n"
                    "property list int uchar tags\n"
                    "property int8 y\n"
                    "property uint z\n"
                    "property float nx\n"
                    "element face 1\n"
                    "property list ushort uint vertex_index\n"
                    "property int16 flags\n"
                    "end_header\n";
    // material: two records with lists of 3 and 0 chars
    put<std::uint16_t>(s, 3, big);
    s += "abc";
    put<double>(s, 1.5, big);
    put<std::uint16_t>(s, 0, big);
    put<double>(s, 2.5, big);
    const long long xyz[3][3] = {{-300, -1, 70000}, {2, 127, 0}, {0, -128, 4000000000LL}};
    for (int v = 0; v < 3; ++v) {
      put<std::int16_t>(s, static_cast<std::int16_t>(xyz[v][0]), big);
      put<std::int32_t>(s, v, big);  // v tags follow
      for (int t = 0; t < v; ++t) put<std::uint8_t>(s, 9, big);
      put<std::int8_t>(s, static_cast<std::int8_t>(xyz[v][1]), big);
      put<std::uint32_t>(s, static_cast<std::uint32_t>(xyz[v][2]), big);
      put<float>(s, 0.5f, big);
    }
    put<std::uint16_t>(s, 3, big);
    for (std::uint32_t i : {2u, 0u, 1u}) put<std::uint32_t>(s, i, big);
    put<std::int16_t>(s, -1, big);
    const auto file = dir.write("ints.ply", s);
    const auto groups = read_mesh_file(file);
    ASSERT_EQ(groups[0].positions.size(), 3u);
    EXPECT_EQ(groups[0].positions[0], Vec3(-300, -1, 70000));
    EXPECT_EQ(groups[0].positions[1], Vec3(2, 127, 0));
    EXPECT_EQ(groups[0].positions[2], Vec3(0, -128, 4e9));
    EXPECT_EQ(groups[0].faces, faces({{2, 0, 1}}));
  }
}

TEST(PlyReader, FacesBeforeVerticesAndNoFaceElement) {
  TempDir dir;
  const auto a = dir.write("order.ply",
                           "ply\nformat ascii 1.0\nelement face 1\n"
                           "property list uchar int vertex_indices\nelement vertex 3\n"
                           "property float x\nproperty float y\nproperty float z\nend_header\n"
                           "3 2 1 0\n0 0 0\n1 0 0\n0 1 0\n");
  EXPECT_EQ(read_mesh_file(a)[0].faces, faces({{2, 1, 0}}));
  const auto b = dir.write("points.ply",
                           "ply\nformat ascii 1.0\nelement vertex 2\n"
                           "property float x\nproperty float y\nproperty float z\nend_header\n"
                           "0 0 0\n1 0 0\n");
  const auto groups = read_mesh_file(b);
  EXPECT_EQ(groups[0].positions.size(), 2u);
  EXPECT_TRUE(groups[0].faces.empty());
}

TEST(PlyReader, TestDataMeshes) {
  const std::filesystem::path dir = std::filesystem::path(VPROXQ_TEST_DATA_DIR) / "meshes";
  const auto cube = read_mesh_file(dir / "cube.ply");
  ASSERT_EQ(cube.size(), 1u);
  EXPECT_EQ(cube[0].name, "cube");
  EXPECT_EQ(cube[0].positions.size(), 8u);
  EXPECT_EQ(cube[0].faces.size(), 12u);
  const auto t0 = read_mesh_file(dir / "thick-cloth/t0.ply");
  const auto t1 = read_mesh_file(dir / "thick-cloth/t1.ply");
  EXPECT_EQ(t0[0].positions.size(), 233u);
  EXPECT_EQ(t0[0].faces.size(), 404u);
  EXPECT_EQ(t0[0].faces, t1[0].faces);
  EXPECT_NE(t0[0].positions, t1[0].positions);
  const auto hf = read_mesh_file(dir / "height-field.ply");
  EXPECT_EQ(hf[0].positions.size(), 2540u);
  EXPECT_EQ(hf[0].faces.size(), 4904u);
}

// ---- errors ----

std::string ascii_header(const std::string& vertex_props, const std::string& rest) {
  return "ply\nformat ascii 1.0\nelement vertex 3\n" + vertex_props + rest;
}
const std::string kXyz = "property float x\nproperty float y\nproperty float z\n";
const std::string kFaces = "element face 1\nproperty list uchar int vertex_indices\n";

TEST(PlyReaderErrors, MissingFile) {
  TempDir dir;
  const auto file = dir.path() / "gone.ply";
  EXPECT_INPUT_ERROR(read_mesh_file(file), file.string() + ": file not found");
}

TEST(PlyReaderErrors, MalformedHeaders) {
  TempDir dir;
  struct Case {
    const char* name;
    std::string text;
    const char* phrase;
  };
  const Case cases[] = {
      {"magic", "plyx\nformat ascii 1.0\nend_header\n", "not a PLY file"},
      {"format", "ply\nformat ebcdic 1.0\nend_header\n", "unknown format 'ebcdic'"},
      {"version", "ply\nformat ascii 2.0\nend_header\n", "unsupported PLY version"},
      {"noformat", "ply\nelement vertex 0\nend_header\n", "no format line"},
      {"noend", ascii_header(kXyz, kFaces), "no end_header"},
      {"orphan", "ply\nformat ascii 1.0\nproperty float x\nend_header\n",
       "property before any element"},
      {"type", ascii_header("property real x\n", "end_header\n"), "unknown type 'real'"},
      {"count", "ply\nformat ascii 1.0\nelement vertex many\nend_header\n",
       "malformed element line"},
      {"keyword", "ply\nformat ascii 1.0\nelemnt vertex 3\nend_header\n",
       "unknown header keyword 'elemnt'"},
      {"novertex", "ply\nformat ascii 1.0\nend_header\n", "no vertex element"},
      {"noz", ascii_header("property float x\nproperty float y\n", "end_header\n0 0\n"),
       "no 'z' property"},
      {"nolist", ascii_header(kXyz, "element face 1\nproperty int a\nend_header\n"),
       "no 'vertex_indices' list"},
      {"floatidx",
       ascii_header(kXyz, "element face 1\nproperty list uchar float vertex_indices\nend_header\n"),
       "integer type"},
      {"floatcount",
       ascii_header(kXyz, "element face 1\nproperty list float int vertex_indices\nend_header\n"),
       "list count type must be an integer type"},
      {"dupprop", ascii_header(kXyz + "property float x\n", "end_header\n"),
       "element 'vertex' declares property 'x' twice"},
      {"dupelement", ascii_header(kXyz, kFaces + "element face 1\nproperty list uchar int vertex_indices\nend_header\n"),
       "element 'face' declared twice"},
      {"tristrips",
       ascii_header(kXyz, "element tristrips 1\nproperty list int int vertex_indices\nend_header\n"),
       "element 'tristrips' (triangle strips) is not supported"},
  };
  for (const Case& c : cases) {
    const auto file = dir.write(std::string(c.name) + ".ply", c.text);
    EXPECT_INPUT_ERROR(read_mesh_file(file), file.string() + ": ", c.phrase);
  }
}

TEST(PlyReaderErrors, TruncatedBinaryData) {
  TempDir dir;
  const std::string full = binary_square<double>(false, "double");
  for (std::size_t cut : {1u, 20u, 100u}) {
    const auto file = dir.write("cut.ply", full.substr(0, full.size() - cut));
    EXPECT_INPUT_ERROR(read_mesh_file(file), file.string() + ": truncated binary data");
  }
  const auto file = dir.write("cut_vertex.ply", full.substr(0, full.size() - 60));
  EXPECT_INPUT_ERROR(read_mesh_file(file), "element 'vertex' record 2 (0-based) of 4");
}

TEST(PlyReaderErrors, AsciiDataProblems) {
  TempDir dir;
  const auto eof =
      dir.write("eof.ply", ascii_header(kXyz, kFaces + "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1"));
  EXPECT_INPUT_ERROR(read_mesh_file(eof), eof.string() + ": unexpected end of file",
                     "element 'face' record 0 (0-based) of 1");
  const auto bad = dir.write(
      "bad.ply", ascii_header(kXyz, kFaces + "end_header\n0 0 0\n1 zero 0\n0 1 0\n3 0 1 2\n"));
  EXPECT_INPUT_ERROR(read_mesh_file(bad), bad.string() + ": line 11: expected a number",
                     "got 'zero'");
  const auto idx = dir.write(
      "idx.ply", ascii_header(kXyz, kFaces + "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2.0\n"));
  EXPECT_INPUT_ERROR(read_mesh_file(idx), idx.string() + ": line 13: expected an integer");
  // A second face past the header's count: the counts do not describe the data. Trailing
  // whitespace is fine.
  const auto more = dir.write(
      "more.ply", ascii_header(kXyz, kFaces + "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n3 2 1 0\n"));
  EXPECT_INPUT_ERROR(read_mesh_file(more), more.string() + ": line 14: '3' after the last element");
  const auto space = dir.write(
      "space.ply", ascii_header(kXyz, kFaces + "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n\n  \n"));
  EXPECT_EQ(read_mesh_file(space)[0].faces.size(), 1u);
}

// Each ascii record is one line (as Greg Turk's reference reader reads them): a row with more
// or fewer values than the header's properties is an error at that line, not a stream of values
// read on into the next record.
TEST(PlyReaderErrors, AsciiRecordsAreLines) {
  TempDir dir;
  struct Case {
    const char* name;
    const char* body;  ///< after the header (its last line is line 9)
    const char* says;
    const char* record;
  };
  for (const Case& c : {
           // Vertex rows that carry normals the header does not declare: the error names the row.
           Case{"normals", "0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n", "line 10: more values than",
                "element 'vertex' record 0 (0-based) of 3: '0' after its last property"},
           // A long row and a short one that make up for each other: read as a stream, vertex 2
           // came out as (0.5, 0, 1) without a word.
           Case{"silent", "0 0 0\n1 0 0 0.5\n0 1\n3 0 1 2\n", "line 11: more values than",
                "element 'vertex' record 1 (0-based) of 3: '0.5'"},
           Case{"short", "0 0 0\n1 0\n0 1 0\n3 0 1 2\n", "line 11: fewer values than",
                "element 'vertex' record 1 (0-based) of 3"},
           // A face whose list is longer or shorter than its count says.
           Case{"long_face", "0 0 0\n1 0 0\n0 1 0\n3 0 1 2 0\n", "line 13: more values than",
                "element 'face' record 0 (0-based) of 1"},
           Case{"split_face", "0 0 0\n1 0 0\n0 1 0\n3 0 1\n2\n", "line 13: fewer values than",
                "element 'face' record 0 (0-based) of 1"}}) {
    SCOPED_TRACE(c.name);
    const auto file = dir.write(std::string(c.name) + ".ply", ascii_header(kXyz, kFaces + "end_header\n" + c.body));
    EXPECT_INPUT_ERROR(read_mesh_file(file), file.string() + ": " + c.says + " the header declares", c.record);
  }
  // Spaces, tabs and CR before the line end are whitespace, not values.
  const auto crlf = dir.write(
      "crlf.ply", ascii_header(kXyz, kFaces + "end_header\r\n0 0 0 \t\r\n1 0 0\r\n\r\n0 1 0\r\n3 0 1 2\r\n"));
  EXPECT_EQ(read_mesh_file(crlf)[0].positions.size(), 3u);
}

// Binary data past the header's counts: as in ascii, the counts (or the property types) do not
// describe the file, so it is not read as if they did.
TEST(PlyReaderErrors, BinaryBytesAfterTheLastElement) {
  TempDir dir;
  for (bool big : {false, true}) {
    const std::string exact = binary_square<double>(big, "double");
    EXPECT_EQ(read_mesh_file(dir.write("exact.ply", exact))[0].faces.size(), 3u);
    const auto one = dir.write("one.ply", exact + "\n");
    EXPECT_INPUT_ERROR(read_mesh_file(one), one.string() + ": 1 byte after the last element the header declares");
    // A third face record that the header does not count.
    std::string face = exact;
    put<std::uint8_t>(face, 3, big);
    for (int i : {0, 1, 2}) put<std::int32_t>(face, i, big);
    const auto more = dir.write("more.ply", face);
    EXPECT_INPUT_ERROR(read_mesh_file(more), more.string() + ": 13 bytes after the last element");
  }
}

TEST(PlyReaderErrors, IndicesOutOfRange) {
  TempDir dir;
  const auto big = dir.write(
      "big.ply", ascii_header(kXyz, kFaces + "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 1 9\n"));
  EXPECT_INPUT_ERROR(
      read_mesh_file(big),
      big.string() + ": face 0 (0-based): vertex index 9 out of range (file has 3 vertices)");
  const auto neg = dir.write(
      "neg.ply", ascii_header(kXyz, kFaces + "end_header\n0 0 0\n1 0 0\n0 1 0\n3 0 -1 2\n"));
  EXPECT_INPUT_ERROR(read_mesh_file(neg),
                     neg.string() + ": face 0 (0-based): vertex index -1 out of range");
}

TEST(PlyReaderErrors, FacesWithFewerThanThreeVertices) {
  TempDir dir;
  const auto file =
      dir.write("two.ply", ascii_header(kXyz, kFaces + "end_header\n0 0 0\n1 0 0\n0 1 0\n2 0 1\n"));
  EXPECT_INPUT_ERROR(read_mesh_file(file), file.string() + ": face 0 (0-based) has 2 vertices");
}

TEST(PlyReaderErrors, NonFiniteCoordinates) {
  TempDir dir;
  const auto a = dir.write("inf.ply", ascii_header(kXyz, "end_header\n0 0 0\n1 0 inf\n0 1 0\n"));
  EXPECT_INPUT_ERROR(read_mesh_file(a),
                     a.string() + ": vertex 1 (0-based) has a non-finite coordinate (z = inf)");
  std::string s =
      "ply\nformat binary_big_endian 1.0\nelement vertex 2\nproperty double x\n"
      "property double y\nproperty double z\nend_header\n";
  for (double v : {0.0, 0.0, 0.0, std::numeric_limits<double>::quiet_NaN(), 0.0, 0.0}) {
    put<double>(s, v, true);
  }
  const auto b = dir.write("nan.ply", s);
  EXPECT_INPUT_ERROR(read_mesh_file(b), b.string() + ": vertex 1 (0-based)", "x = nan");
}

TEST(PlyReaderErrors, CoordinatesOutOfRange) {
  TempDir dir;
  std::string s =
      "ply\nformat binary_little_endian 1.0\nelement vertex 2\nproperty double x\n"
      "property double y\nproperty double z\nend_header\n";
  for (double v : {0.0, 0.0, 0.0, 0.0, 0x1p200, 0.0}) put<double>(s, v, false);
  const auto a = dir.write("far.ply", s);
  EXPECT_INPUT_ERROR(read_mesh_file(a), a.string() + ": vertex 1 (0-based) has a coordinate out of range (y = 1.6069380442589903e+60;");
  const auto b = dir.write("far_ascii.ply", ascii_header("property double x\nproperty double y\nproperty double z\n", "end_header\n0 0 0\n1 0 0\n0 -3e70 0\n"));
  EXPECT_INPUT_ERROR(read_mesh_file(b), b.string() + ": vertex 2 (0-based)", "y = -3e+70;");
}

}  // namespace
}  // namespace vproxq
