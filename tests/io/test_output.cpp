// ResultWriter: results.json and results.h5 contents, atomic commit, abort and error paths.
#include "core/errors.hpp"
#include "io/hdf5_reader.hpp"
#include "io/output.hpp"
#include "io/pipeline.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <limits>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <unistd.h>

namespace vproxq {
namespace {

namespace fs = std::filesystem;
using nlohmann::json;

std::uint64_t bits(double x) {
  std::uint64_t b;
  std::memcpy(&b, &x, sizeof b);
  return b;
}

// Doubles whose shortest decimal forms are long or unusual: they must come back bit for bit.
const double kTricky[] = {0.1,
                          1.0 / 3.0,
                          2.0 / 3.0 * 1e-17,
                          5e-324,  // smallest subnormal
                          std::numeric_limits<double>::max(),
                          std::nextafter(1.0, 2.0),
                          -0.0,
                          123456789.123456789,
                          -7.2e300};

std::string read_text(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::stringstream ss;
  ss << in.rdbuf();
  return ss.str();
}

std::set<std::string> keys_of(const json& object) {
  std::set<std::string> keys;
  for (auto it = object.begin(); it != object.end(); ++it) keys.insert(it.key());
  return keys;
}

std::vector<std::string> dir_entries(const fs::path& dir) {
  std::vector<std::string> names;
  for (const auto& e : fs::directory_iterator(dir)) names.push_back(e.path().filename().string());
  std::sort(names.begin(), names.end());
  return names;
}

// The documented file codes of the `case` field.
int case_code(TriangleDistanceCase kind) {
  switch (kind) {
    case TriangleDistanceCase::Intersecting: return 0;
    case TriangleDistanceCase::VertexFace: return 1;
    case TriangleDistanceCase::FaceVertex: return 2;
    case TriangleDistanceCase::EdgeEdge: return 3;
  }
  return -1;
}

RunInfo make_info() {
  RunInfo info;
  info.scene = "scenes/bowl/scene.json";
  info.scene_name = "bowl";
  info.queries = {"distance", "ccd"};
  info.voronoi = "cpu";
  info.grid = 64;
  info.device = "";
  info.threads = 3;
  info.frame_count = 3;
  return info;
}

InterObjectDistance make_inter(Index object, Index nearest, double distance, Index ta, Index tb,
                               Vec3 pa, Vec3 pb, TriangleDistanceCase kind) {
  InterObjectDistance d;
  d.object = object;
  d.nearest_object = nearest;
  d.distance = distance;
  d.triangles = {ta, tb};
  d.points = {pa, pb};
  d.kind = kind;
  return d;
}

// Frame 0: three objects (one static), all with a nearest object, tricky doubles.
// Frame 1: "distance" did not run. Frame 2: a lone object (no nearest), no files.
std::vector<FrameResult> make_frames() {
  std::vector<FrameResult> frames(3);

  FrameResult& f0 = frames[0];
  f0.frame = 0;
  f0.files = {"frames/bowl_0000.obj", "bowl.obj"};
  f0.objects = {{0, "blob0", 162, 320, false}, {1, "blob1", 4, 2, false},
                {2, "bowl", 1000, 1996, true}};
  f0.inter = std::vector<InterObjectDistance>{
      make_inter(0, 2, kTricky[0], 12, 40, Vec3(kTricky[1], kTricky[2], kTricky[3]),
                 Vec3(kTricky[4], kTricky[5], kTricky[6]), TriangleDistanceCase::VertexFace),
      make_inter(1, 2, 0.0, 1, 1995, Vec3(kTricky[7], kTricky[8], 1.5), Vec3(kTricky[7], kTricky[8], 1.5),
                 TriangleDistanceCase::Intersecting),
      make_inter(2, 1, 0.0, 1995, 1, Vec3(kTricky[7], kTricky[8], 1.5), Vec3(kTricky[7], kTricky[8], 1.5),
                 TriangleDistanceCase::EdgeEdge)};
  f0.counters = {6, 1234, 567, 89};
  f0.time_ms = {1.5, 0.25, 3.125, 7.0, 99.0, 12.0};

  FrameResult& f1 = frames[1];
  f1.frame = 1;
  f1.files = {"frames/bowl_0001.obj", "bowl.obj"};
  f1.objects = f0.objects;
  f1.counters = {0, 0, 0};
  f1.time_ms = {0.5, 0, 0, 0, 0, 0.75};

  FrameResult& f2 = frames[2];
  f2.frame = 2;
  f2.objects = {{0, "solo \"quoted\" \xc3\xa9", 3, 1, false}};
  InterObjectDistance lone;
  lone.object = 0;
  f2.inter = std::vector<InterObjectDistance>{lone};
  f2.counters = {std::uint64_t{1} << 40, 0, 0};
  f2.time_ms = {0, 0, 0, 0, 0, 0};
  return frames;
}

class OutputTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("vproxq_test_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  // Writes `frames` to OUT = dir_/out and commits; returns the ms write_frame reported.
  std::vector<double> write_all(const RunInfo& info, const std::vector<FrameResult>& frames) {
    ResultWriter writer(out(), info);
    std::vector<double> ms;
    for (const FrameResult& f : frames) ms.push_back(writer.write_frame(f));
    writer.commit();
    return ms;
  }

  fs::path out() const { return dir_ / "out"; }

  fs::path dir_;
};

TEST_F(OutputTest, CommitWritesBothFilesAndNoTemporaries) {
  write_all(make_info(), make_frames());
  EXPECT_EQ(dir_entries(out()), (std::vector<std::string>{"results.h5", "results.json"}));
}

TEST_F(OutputTest, JsonHeaderHasExactlyTheDocumentedKeys) {
  write_all(make_info(), make_frames());
  const json doc = json::parse(read_text(out() / "results.json"));
  EXPECT_EQ(keys_of(doc), (std::set<std::string>{"tool", "version", "format_version", "scene",
                                                 "queries", "settings", "frames"}));
  EXPECT_EQ(doc["tool"], "vproxq");
  EXPECT_EQ(doc["version"], VPROXQ_VERSION);
  EXPECT_EQ(doc["format_version"], 1);
  EXPECT_EQ(doc["scene"], "bowl");
  EXPECT_EQ(doc["queries"], json::array({"distance", "ccd"}));
  EXPECT_EQ(keys_of(doc["settings"]),
            (std::set<std::string>{"voronoi", "grid", "device", "threads", "self"}));
  EXPECT_EQ(doc["settings"]["voronoi"], "cpu");
  EXPECT_EQ(doc["settings"]["self"], true);
  EXPECT_EQ(doc["settings"]["grid"], 64);
  EXPECT_TRUE(doc["settings"]["device"].is_null());
  EXPECT_EQ(doc["settings"]["threads"], 3);
  ASSERT_TRUE(doc["frames"].is_array());
  EXPECT_EQ(doc["frames"].size(), 3u);
}

TEST_F(OutputTest, JsonSettingsGridNullWhenZeroAndDeviceStringWhenSet) {
  RunInfo info = make_info();
  info.grid = 0;
  info.voronoi = "gpu";
  info.device = "llvmpipe (LLVM 15.0.6, 256 bits)";
  write_all(info, {});
  const json doc = json::parse(read_text(out() / "results.json"));
  EXPECT_TRUE(doc["settings"]["grid"].is_null());
  EXPECT_EQ(doc["settings"]["device"], "llvmpipe (LLVM 15.0.6, 256 bits)");
  EXPECT_EQ(doc["frames"], json::array());
}

TEST_F(OutputTest, JsonFramesHoldEveryValueAndDoublesRoundTripBitwise) {
  const std::vector<FrameResult> frames = make_frames();
  const std::vector<double> ms = write_all(make_info(), frames);
  const json doc = json::parse(read_text(out() / "results.json"));

  for (std::size_t k = 0; k < frames.size(); ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    const FrameResult& f = frames[k];
    const json& jf = doc["frames"][k];
    std::set<std::string> expected_keys{"frame", "objects", "stats"};
    if (f.inter) expected_keys.insert("distance");
    EXPECT_EQ(keys_of(jf), expected_keys);
    EXPECT_EQ(jf["frame"], f.frame);

    ASSERT_EQ(jf["objects"].size(), f.objects.size());
    for (std::size_t i = 0; i < f.objects.size(); ++i) {
      const json& o = jf["objects"][i];
      const ObjectInfo& e = f.objects[i];
      std::set<std::string> keys{"id", "name", "vertices", "triangles"};
      if (e.is_static) keys.insert("static");
      EXPECT_EQ(keys_of(o), keys);
      EXPECT_EQ(o["id"], e.id);
      EXPECT_EQ(o["name"], e.name);
      EXPECT_EQ(o["vertices"], e.vertices);
      EXPECT_EQ(o["triangles"], e.triangles);
      if (e.is_static) {
        EXPECT_EQ(o["static"], true);
      }
    }

    if (f.inter) {
      EXPECT_EQ(keys_of(jf["distance"]), std::set<std::string>{"inter"});
      const json& inter = jf["distance"]["inter"];
      ASSERT_EQ(inter.size(), f.inter->size());
      for (std::size_t i = 0; i < inter.size(); ++i) {
        const InterObjectDistance& e = (*f.inter)[i];
        const json& r = inter[i];
        EXPECT_EQ(keys_of(r), (std::set<std::string>{"object", "nearest_object", "distance",
                                                     "triangles", "points"}));
        EXPECT_EQ(r["object"], e.object);
        if (!e.has_nearest()) {
          EXPECT_TRUE(r["nearest_object"].is_null());
          EXPECT_TRUE(r["distance"].is_null());
          EXPECT_TRUE(r["triangles"].is_null());
          EXPECT_TRUE(r["points"].is_null());
          continue;
        }
        EXPECT_EQ(r["nearest_object"], e.nearest_object);
        EXPECT_EQ(bits(r["distance"].get<double>()), bits(e.distance));
        EXPECT_EQ(r["triangles"], json::array({e.triangles[0], e.triangles[1]}));
        ASSERT_EQ(r["points"].size(), 2u);
        for (int p = 0; p < 2; ++p) {
          ASSERT_EQ(r["points"][p].size(), 3u);
          for (int c = 0; c < 3; ++c) {
            EXPECT_EQ(bits(r["points"][p][c].get<double>()), bits(e.points[p][c]))
                << "point " << p << " coordinate " << c;
          }
        }
      }
    }

    const json& stats = jf["stats"];
    EXPECT_EQ(keys_of(stats), (std::set<std::string>{"time_ms", "exact_tests", "pns_pairs",
                                                     "feature_pns", "separation_culled"}));
    EXPECT_EQ(keys_of(stats["time_ms"]), (std::set<std::string>{"load", "aabb", "voronoi",
                                                                "exact", "write", "total"}));
    EXPECT_EQ(stats["time_ms"]["load"].get<double>(), f.time_ms.load);
    EXPECT_EQ(stats["time_ms"]["aabb"].get<double>(), f.time_ms.aabb);
    EXPECT_EQ(stats["time_ms"]["voronoi"].get<double>(), f.time_ms.voronoi);
    EXPECT_EQ(stats["time_ms"]["exact"].get<double>(), f.time_ms.exact);
    EXPECT_EQ(stats["time_ms"]["total"].get<double>(), f.time_ms.total);
    // write is measured by the writer (not copied from the FrameResult) and is part of what
    // write_frame returned.
    const double write = stats["time_ms"]["write"].get<double>();
    EXPECT_GE(write, 0.0);
    EXPECT_LE(write, ms[k]);
    EXPECT_NE(write, 99.0);
    EXPECT_EQ(stats["exact_tests"].get<std::uint64_t>(), f.counters.exact_tests);
    EXPECT_EQ(stats["pns_pairs"].get<std::uint64_t>(), f.counters.object_pns_pairs);
    EXPECT_EQ(stats["feature_pns"].get<std::uint64_t>(), f.counters.feature_pns);
    EXPECT_EQ(stats["separation_culled"].get<std::uint64_t>(), f.counters.separation_culled);
  }
}

TEST_F(OutputTest, JsonKeepsDocumentedKeyOrderAndOneRecordPerLine) {
  write_all(make_info(), make_frames());
  const std::string text = read_text(out() / "results.json");
  // Top-level and per-frame keys in DESIGN.md order.
  const char* order[] = {"\"tool\"", "\"version\"", "\"format_version\"", "\"scene\"",
                         "\"queries\"", "\"settings\"", "\"frames\"", "\"frame\"",
                         "\"objects\"", "\"distance\"", "\"stats\""};
  std::size_t at = 0;
  for (const char* key : order) {
    const std::size_t next = text.find(key, at);
    ASSERT_NE(next, std::string::npos) << key;
    at = next;
  }
  // Each object record and each inter record sits on its own line.
  std::istringstream lines(text);
  std::string line;
  int object_lines = 0, inter_lines = 0;
  while (std::getline(lines, line)) {
    if (line.find("{\"id\":") != std::string::npos) ++object_lines;
    if (line.find("{\"object\":") != std::string::npos) ++inter_lines;
  }
  EXPECT_EQ(object_lines, 3 + 3 + 1);
  EXPECT_EQ(inter_lines, 3 + 1);
  EXPECT_EQ(text.back(), '\n');
}

TEST_F(OutputTest, Hdf5RootAttributesCarryTheSettings) {
  write_all(make_info(), make_frames());
  Hdf5Reader h5(out() / "results.h5");
  EXPECT_EQ(h5.attribute_names("/"),
            (std::vector<std::string>{"device", "format_version", "grid", "queries", "scene",
                                      "scene_path", "self", "threads", "tool", "version", "voronoi"}));
  EXPECT_EQ(h5.int_attribute("/", "self"), 1);
  EXPECT_EQ(h5.string_attribute("/", "tool"), "vproxq");
  EXPECT_EQ(h5.string_attribute("/", "version"), VPROXQ_VERSION);
  EXPECT_EQ(h5.int_attribute("/", "format_version"), 1);
  EXPECT_EQ(h5.string_attribute("/", "scene"), "bowl");
  EXPECT_EQ(h5.string_attribute("/", "scene_path"), "scenes/bowl/scene.json");
  EXPECT_EQ(h5.string_attribute("/", "queries"), "distance,ccd");
  EXPECT_EQ(h5.string_attribute("/", "voronoi"), "cpu");
  EXPECT_EQ(h5.int_attribute("/", "grid"), 64);
  EXPECT_EQ(h5.string_attribute("/", "device"), "");
  EXPECT_EQ(h5.int_attribute("/", "threads"), 3);
  EXPECT_EQ(h5.children("/"), std::vector<std::string>{"frames"});
  EXPECT_EQ(h5.children("/frames"), (std::vector<std::string>{"000000", "000001", "000002"}));
}

TEST_F(OutputTest, Hdf5FramesHoldEveryValue) {
  const std::vector<FrameResult> frames = make_frames();
  write_all(make_info(), frames);
  Hdf5Reader h5(out() / "results.h5");

  for (std::size_t k = 0; k < frames.size(); ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    const FrameResult& f = frames[k];
    char name[16];
    std::snprintf(name, sizeof name, "/frames/%06d", f.frame);
    const std::string g = name;

    EXPECT_EQ(h5.attribute_names(g), (std::vector<std::string>{"files", "frame"}));
    EXPECT_EQ(h5.int_attribute(g, "frame"), f.frame);
    EXPECT_EQ(h5.strings_attribute(g, "files"), f.files);
    std::vector<std::string> children{"object_names", "objects", "stats"};
    if (f.inter) children.insert(children.begin(), "distance");
    EXPECT_EQ(h5.children(g), children);

    EXPECT_EQ(h5.field_names(g + "/objects"),
              (std::vector<std::string>{"id", "vertices", "triangles", "is_static"}));
    ASSERT_EQ(h5.rows(g + "/objects"), f.objects.size());
    const auto ids = h5.int_field(g + "/objects", "id");
    const auto vertices = h5.int_field(g + "/objects", "vertices");
    const auto triangles = h5.int_field(g + "/objects", "triangles");
    const auto is_static = h5.int_field(g + "/objects", "is_static");
    const auto names = h5.strings_dataset(g + "/object_names");
    ASSERT_EQ(names.size(), f.objects.size());
    for (std::size_t i = 0; i < f.objects.size(); ++i) {
      EXPECT_EQ(ids[i], f.objects[i].id);
      EXPECT_EQ(vertices[i], f.objects[i].vertices);
      EXPECT_EQ(triangles[i], f.objects[i].triangles);
      EXPECT_EQ(is_static[i], f.objects[i].is_static ? 1 : 0);
      EXPECT_EQ(names[i], f.objects[i].name);
    }

    EXPECT_EQ(h5.exists(g + "/distance/inter"), f.inter.has_value());
    if (f.inter) {
      const std::string d = g + "/distance/inter";
      EXPECT_EQ(h5.field_names(d),
                (std::vector<std::string>{"object", "nearest_object", "distance", "tri_a",
                                          "tri_b", "point_a", "point_b", "case"}));
      ASSERT_EQ(h5.rows(d), f.inter->size());
      const auto object = h5.int_field(d, "object");
      const auto nearest = h5.int_field(d, "nearest_object");
      const auto distance = h5.double_field(d, "distance");
      const auto tri_a = h5.int_field(d, "tri_a");
      const auto tri_b = h5.int_field(d, "tri_b");
      const auto point_a = h5.double_field(d, "point_a");
      const auto point_b = h5.double_field(d, "point_b");
      const auto kind = h5.int_field(d, "case");
      ASSERT_EQ(point_a.size(), 3 * f.inter->size());
      ASSERT_EQ(point_b.size(), 3 * f.inter->size());
      for (std::size_t i = 0; i < f.inter->size(); ++i) {
        const InterObjectDistance& e = (*f.inter)[i];
        EXPECT_EQ(object[i], e.object);
        if (!e.has_nearest()) {
          EXPECT_EQ(nearest[i], -1);
          EXPECT_TRUE(std::isinf(distance[i]) && distance[i] > 0);
          EXPECT_EQ(tri_a[i], -1);
          EXPECT_EQ(tri_b[i], -1);
          for (int c = 0; c < 3; ++c) EXPECT_TRUE(std::isnan(point_a[3 * i + c]));
          EXPECT_EQ(kind[i], 255);
          continue;
        }
        EXPECT_EQ(nearest[i], e.nearest_object);
        EXPECT_EQ(bits(distance[i]), bits(e.distance));
        EXPECT_EQ(tri_a[i], e.triangles[0]);
        EXPECT_EQ(tri_b[i], e.triangles[1]);
        for (int c = 0; c < 3; ++c) {
          EXPECT_EQ(bits(point_a[3 * i + c]), bits(e.points[0][c]));
          EXPECT_EQ(bits(point_b[3 * i + c]), bits(e.points[1][c]));
        }
        EXPECT_EQ(kind[i], case_code(e.kind));
      }
    }

    const std::string s = g + "/stats";
    EXPECT_EQ(h5.attribute_names(s),
              (std::vector<std::string>{"exact_tests", "feature_pns", "pns_pairs",
                                        "separation_culled", "time_ms_aabb", "time_ms_exact", "time_ms_load",
                                        "time_ms_total", "time_ms_voronoi", "time_ms_write"}));
    EXPECT_EQ(h5.double_attribute(s, "time_ms_load"), f.time_ms.load);
    EXPECT_EQ(h5.double_attribute(s, "time_ms_aabb"), f.time_ms.aabb);
    EXPECT_EQ(h5.double_attribute(s, "time_ms_voronoi"), f.time_ms.voronoi);
    EXPECT_EQ(h5.double_attribute(s, "time_ms_exact"), f.time_ms.exact);
    EXPECT_EQ(h5.double_attribute(s, "time_ms_total"), f.time_ms.total);
    EXPECT_GE(h5.double_attribute(s, "time_ms_write"), 0.0);
    EXPECT_EQ(h5.uint_attribute(s, "exact_tests"), f.counters.exact_tests);
    EXPECT_EQ(h5.uint_attribute(s, "pns_pairs"), f.counters.object_pns_pairs);
    EXPECT_EQ(h5.uint_attribute(s, "feature_pns"), f.counters.feature_pns);
    EXPECT_EQ(h5.uint_attribute(s, "separation_culled"), f.counters.separation_culled);
  }
}

TEST_F(OutputTest, Hdf5AndJsonRecordTheSameWriteTime) {
  const std::vector<FrameResult> frames = make_frames();
  write_all(make_info(), frames);
  const json doc = json::parse(read_text(out() / "results.json"));
  Hdf5Reader h5(out() / "results.h5");
  EXPECT_EQ(bits(h5.double_attribute("/frames/000000/stats", "time_ms_write")),
            bits(doc["frames"][0]["stats"]["time_ms"]["write"].get<double>()));
}

TEST_F(OutputTest, NamesThatAreNotUtf8AreTheSameValidTextInBothFiles) {
  // Object names come from mesh files and may hold any bytes. The HDF5 strings are declared
  // UTF-8, so invalid sequences become U+FFFD there as in results.json.
  std::vector<FrameResult> frames = make_frames();
  frames[0].objects[0].name = "bad\xff\xfe name \xc3\xa9 \xc3";
  frames[0].files[0] = "frames/\xe9t\xe9.obj";
  write_all(make_info(), frames);
  const json doc = json::parse(read_text(out() / "results.json"));
  Hdf5Reader h5(out() / "results.h5");
  const std::string name = doc["frames"][0]["objects"][0]["name"].get<std::string>();
  EXPECT_EQ(name, "bad\xef\xbf\xbd\xef\xbf\xbd name \xc3\xa9 \xef\xbf\xbd");
  EXPECT_EQ(h5.strings_dataset("/frames/000000/object_names")[0], name);
  EXPECT_EQ(h5.strings_attribute("/frames/000000", "files")[0], "frames/\xef\xbf\xbdt\xef\xbf\xbd.obj");
  EXPECT_EQ(h5.strings_dataset("/frames/000000/object_names")[1], "blob1");
}

// The HDF5 writer closes and reopens its file every 1000 frames (to keep memory flat).
TEST_F(OutputTest, ManyFramesAreAllWritten) {
  constexpr int kFrames = 1002;
  {
    ResultWriter writer(out(), make_info());
    FrameResult f = make_frames()[2];
    for (int k = 0; k < kFrames; ++k) {
      f.frame = k;
      f.objects[0].triangles = k;
      writer.write_frame(f);
    }
    writer.commit();
  }
  Hdf5Reader h5(out() / "results.h5");
  const std::vector<std::string> groups = h5.children("/frames");
  ASSERT_EQ(groups.size(), static_cast<std::size_t>(kFrames));
  EXPECT_EQ(groups.back(), "001001");
  for (int k : {0, 999, 1000, 1001}) {
    char name[32];
    std::snprintf(name, sizeof name, "/frames/%06d", k);
    EXPECT_EQ(h5.int_attribute(name, "frame"), k);
    EXPECT_EQ(h5.int_field(std::string(name) + "/objects", "triangles"),
              std::vector<std::int64_t>{k});
    EXPECT_TRUE(h5.exists(std::string(name) + "/stats"));
  }
  const json doc = json::parse(read_text(out() / "results.json"));
  ASSERT_EQ(doc["frames"].size(), static_cast<std::size_t>(kFrames));
  EXPECT_EQ(doc["frames"][1001]["objects"][0]["triangles"], 1001);
}

TEST_F(OutputTest, Hdf5FileIsReadableByH5dump) {
  if (std::system("command -v h5dump > /dev/null 2>&1") != 0) GTEST_SKIP() << "no h5dump";
  write_all(make_info(), make_frames());
  const std::string command =
      "h5dump '" + (out() / "results.h5").string() + "' > '" + (dir_ / "dump.txt").string() + "'";
  ASSERT_EQ(std::system(command.c_str()), 0);
  const std::string dump = read_text(dir_ / "dump.txt");
  EXPECT_NE(dump.find("GROUP \"000002\""), std::string::npos);
  EXPECT_NE(dump.find("\"point_a\""), std::string::npos);
}

TEST_F(OutputTest, AbortLeavesNoFiles) {
  {
    ResultWriter writer(out(), make_info());
    writer.write_frame(make_frames()[0]);
    EXPECT_EQ(dir_entries(out()).size(), 2u);  // the two temporaries
  }
  EXPECT_FALSE(fs::exists(out())) << "the writer created it, so an abort removes it";

  // An existing directory stays, emptied of the temporaries only.
  fs::create_directories(out());
  std::ofstream(out() / "mine.txt") << "kept\n";
  {
    ResultWriter writer(out(), make_info());
    writer.write_frame(make_frames()[0]);
  }
  EXPECT_EQ(dir_entries(out()), std::vector<std::string>{"mine.txt"});
}

// BackgroundWriter: the same files as ResultWriter (but for each frame's write time), frames
// in the order given, each write done before the next one starts.
TEST_F(OutputTest, BackgroundWriterWritesWhatTheWriterWrites) {
  write_all(make_info(), make_frames());
  const fs::path direct = dir_ / "direct";
  fs::rename(out(), direct);
  {
    BackgroundWriter writer(std::make_unique<ResultWriter>(out(), make_info()), 0.0);  // all on the worker
    for (FrameResult f : make_frames()) writer.write_frame(std::move(f));
    writer.commit();
  }
  EXPECT_EQ(dir_entries(out()), (std::vector<std::string>{"results.h5", "results.json"}));
  json a = json::parse(read_text(direct / "results.json"));
  json b = json::parse(read_text(out() / "results.json"));
  ASSERT_EQ(a["frames"].size(), make_frames().size());
  ASSERT_EQ(b["frames"].size(), a["frames"].size());
  for (std::size_t k = 0; k < a["frames"].size(); ++k) {
    EXPECT_GE(b["frames"][k]["stats"]["time_ms"]["write"].get<double>(), 0.0);
    a["frames"][k]["stats"]["time_ms"].erase("write");
    b["frames"][k]["stats"]["time_ms"].erase("write");
  }
  EXPECT_EQ(a, b);
  Hdf5Reader h5(out() / "results.h5");
  EXPECT_EQ(h5.children("/frames").size(), make_frames().size());
}

// Without commit(), nothing is left, also when the last write is still running; a write's
// error comes back from the next call that waits for it.
TEST_F(OutputTest, BackgroundWriterAbortAndErrors) {
  {
    BackgroundWriter writer(std::make_unique<ResultWriter>(out(), make_info()), 0.0);
    for (FrameResult f : make_frames()) writer.write_frame(std::move(f));
  }
  EXPECT_FALSE(fs::exists(out()));
  {
    BackgroundWriter writer(std::make_unique<ResultWriter>(out(), make_info()), 0.0);
    writer.write_frame(make_frames()[0]);
    writer.commit();
    writer.write_frame(make_frames()[1]);  // fails on the writer's thread: already committed
    try {
      writer.write_frame(make_frames()[2]);  // waits for the failed write
      ADD_FAILURE() << "the failed write was not reported";
    } catch (const RuntimeError& e) {
      EXPECT_NE(std::string(e.what()).find("already committed"), std::string::npos) << e.what();
    }
  }
  const json doc = json::parse(read_text(out() / "results.json"));
  EXPECT_EQ(doc["frames"].size(), 1u);
}

TEST_F(OutputTest, AbortKeepsEarlierResultsIntact) {
  write_all(make_info(), make_frames());
  const std::string json_before = read_text(out() / "results.json");
  const std::string h5_before = read_text(out() / "results.h5");
  {
    RunInfo other = make_info();
    other.scene_name = "other";
    ResultWriter writer(out(), other);
    FrameResult f = make_frames()[1];
    writer.write_frame(f);
    // destroyed without commit, as when a later frame throws
  }
  EXPECT_EQ(dir_entries(out()), (std::vector<std::string>{"results.h5", "results.json"}));
  EXPECT_EQ(read_text(out() / "results.json"), json_before);
  EXPECT_EQ(read_text(out() / "results.h5"), h5_before);
}

TEST_F(OutputTest, CommitReplacesEarlierResults) {
  write_all(make_info(), make_frames());
  RunInfo other = make_info();
  other.scene_name = "other";
  write_all(other, {make_frames()[1]});
  const json doc = json::parse(read_text(out() / "results.json"));
  EXPECT_EQ(doc["scene"], "other");
  EXPECT_EQ(doc["frames"].size(), 1u);
  EXPECT_EQ(Hdf5Reader(out() / "results.h5").children("/frames"),
            std::vector<std::string>{"000001"});
}

TEST_F(OutputTest, CreatesMissingOutputDirectories) {
  const fs::path nested = dir_ / "a" / "b" / "c";
  {
    ResultWriter writer(nested, make_info());
    writer.commit();
  }
  EXPECT_TRUE(fs::exists(nested / "results.json"));
  EXPECT_TRUE(fs::exists(nested / "results.h5"));
}

TEST_F(OutputTest, UnwritableOutputDirectoryThrowsRuntimeErrorNamingIt) {
  fs::create_directories(dir_);
  std::ofstream(dir_ / "plain_file") << "not a directory";
  const fs::path bad = dir_ / "plain_file" / "out";
  try {
    ResultWriter writer(bad, make_info());
    FAIL() << "expected RuntimeError";
  } catch (const RuntimeError& e) {
    EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(ResultWriter(dir_ / "plain_file", make_info()), RuntimeError);
}

TEST_F(OutputTest, DuplicateFrameFailsAndBlocksCommit) {
  {
    ResultWriter writer(out(), make_info());
    writer.write_frame(make_frames()[0]);
    try {
      writer.write_frame(make_frames()[0]);  // /frames/000000 exists already
      FAIL() << "expected RuntimeError";
    } catch (const RuntimeError& e) {
      EXPECT_NE(std::string(e.what()).find("H5Gcreate2"), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find("/frames/000000"), std::string::npos) << e.what();
    }
    EXPECT_THROW(writer.commit(), RuntimeError);
  }
  EXPECT_FALSE(fs::exists(out()));
}

TEST_F(OutputTest, WriteAfterCommitThrows) {
  ResultWriter writer(out(), make_info());
  writer.commit();
  EXPECT_THROW(writer.write_frame(make_frames()[0]), RuntimeError);
  EXPECT_THROW(writer.commit(), RuntimeError);
}

TEST_F(OutputTest, Hdf5ReaderRejectsMissingFile) {
  EXPECT_THROW(Hdf5Reader(dir_ / "nope.h5"), InputError);
}

}  // namespace
}  // namespace vproxq
