// SceneSource: scene.json variants, bare mesh files, frame loading, and every bad key.
#include "io/pipeline.hpp"
#include "io/scene_source.hpp"
#include "io_test_util.hpp"

#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <stdexcept>

namespace vproxq {
namespace {

namespace fs = std::filesystem;
using test::TempDir;

/// An OBJ file with one triangle per group, each with its own three vertices, moved by
/// `shift` along x (so frames differ in positions only). An empty name writes no o line.
std::string triangles_obj(const std::vector<std::string>& groups, double shift = 0) {
  std::string s;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    if (!groups[g].empty()) s += "o " + groups[g] + "\n";
    const double x = shift + 10.0 * static_cast<double>(g);
    s += "v " + std::to_string(x) + " 0 0\nv " + std::to_string(x + 1) + " 0 0\nv " +
         std::to_string(x) + " 1 0\nf -3 -2 -1\n";
  }
  return s;
}

const std::string kCubeObj =
    "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
    "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 2 3 7 6\nf 3 4 8 7\nf 4 1 5 8\n";

class SceneSourceTest : public ::testing::Test {
 protected:
  fs::path scene(const std::string& json) { return dir.write("scene.json", json); }
  TempDir dir;
};

TEST_F(SceneSourceTest, PatternFramesLoadOnRequest) {
  for (int k = 2; k < 5; ++k) {
    char name[64];
    std::snprintf(name, sizeof name, "frames/f_%03d.obj", k);
    dir.write(name, triangles_obj({"a", "b"}, k));
  }
  const auto path = scene(R"({"name": "demo",
      "frames": {"pattern": "frames/f_%03d.obj", "first": 2, "count": 3},
      "queries": ["distance", "ccd"], "grid": 64})");
  const SceneSource s = SceneSource::open(path);
  EXPECT_EQ(s.name(), "demo");
  EXPECT_EQ(s.path(), path);
  EXPECT_EQ(s.frame_count(), 3u);
  EXPECT_EQ(s.queries(), (std::vector<std::string>{"distance", "ccd"}));
  EXPECT_EQ(s.grid(), 64);
  EXPECT_EQ(s.self(), std::nullopt);
  EXPECT_EQ(s.split(), ObjectSplit::Meshes);

  const Frame f1 = s.load_frame(1);
  EXPECT_EQ(f1.index, 1);
  EXPECT_EQ(f1.files, (std::vector<std::string>{(dir.path() / "frames/f_003.obj").string()}));
  ASSERT_EQ(f1.objects.size(), 2u);
  EXPECT_EQ(f1.objects[0].name, "a");
  EXPECT_EQ(f1.objects[1].name, "b");
  EXPECT_FALSE(f1.objects[0].is_static);
  EXPECT_EQ(f1.objects[1].positions[0], Vec3(13, 0, 0));
  EXPECT_EQ(f1.objects[1].topology->faces, (std::vector<Face>{{0, 1, 2}}));
  EXPECT_EQ(f1.objects[1].num_vertices(), 3);

  // Unchanged faces: the same topology object is handed out again.
  const Frame f2 = s.load_frame(2);
  EXPECT_EQ(f2.objects[1].positions[0], Vec3(14, 0, 0));
  EXPECT_EQ(f1.objects[0].topology.get(), f2.objects[0].topology.get());
  EXPECT_EQ(f1.objects[1].topology.get(), f2.objects[1].topology.get());
  EXPECT_NE(f2.objects[0].topology.get(), f2.objects[1].topology.get());
}

// FrameFileCheck::Deferred: open() checks no frame file, require_frames() the ones asked for,
// with open()'s message; a huge "count" costs nothing (file names are made when asked for).
TEST_F(SceneSourceTest, DeferredFrameChecksCoverOnlyTheFramesAskedFor) {
  dir.write("f_0.obj", triangles_obj({"a"}));
  dir.write("f_1.obj", triangles_obj({"a"}, 1));
  for (const std::string& per_object : {std::string("0"), std::string("1")}) {
    SCOPED_TRACE(per_object);
    const std::string frames = R"({"pattern": "f_%d.obj", "count": 2147483647})";
    const auto path = scene(per_object == "1" ? R"({"objects": [{"name": "a", "frames": )" + frames + "}]}"
                                              : R"({"frames": )" + frames + "}");
    const std::string key = per_object == "1" ? "\"objects[0].frames.pattern\"" : "\"frames.pattern\"";
    EXPECT_INPUT_ERROR(SceneSource::open(path), path.string() + ": " + key + " frame 2: file not found: ",
                       (dir.path() / "f_2.obj").string());
    const SceneSource s = SceneSource::open(path, FrameFileCheck::Deferred);
    EXPECT_EQ(s.frame_count(), 2147483647u);
    s.require_frames(0, 2);
    s.require_frames(1, 1);
    EXPECT_EQ(s.load_frame(1).objects[0].positions[0], Vec3(1, 0, 0));
    EXPECT_INPUT_ERROR(s.require_frames(1, 3), path.string() + ": " + key + " frame 2: file not found: ");
    EXPECT_INPUT_ERROR(s.load_frame(5), (dir.path() / "f_5.obj").string() + ": file not found");
  }
  const auto listed = scene(R"({"frames": {"files": ["f_0.obj", "gone.obj", "f_1.obj"]}})");
  const SceneSource s = SceneSource::open(listed, FrameFileCheck::Deferred);
  s.require_frames(2, 3);
  EXPECT_INPUT_ERROR(s.require_frames(0, 3), listed.string() + ": \"frames.files[1]\" frame 1: file not found: ");
}

// FrameReadAhead hands out frames first .. end-1 in order, as load_frame() gives them (the
// topologies of unchanged faces shared, which needs the reads in order), and a frame's read
// error only when that frame is asked for: the frames before it come back whole even when its
// read (started as soon as the one before it was handed out) has failed meanwhile.
TEST_F(SceneSourceTest, FramesAreReadAheadInOrderWithTheirOwnErrors) {
  for (int k = 0; k < 5; ++k) {
    char name[64];
    std::snprintf(name, sizeof name, "frames/f_%d.obj", k);
    dir.write(name, k == 3 ? std::string("o a\nv 0 0 zero\n") : triangles_obj({"a", "b"}, k));
  }
  // inline_ms 0: every read after the first on the worker; 1e9: every read in line.
  for (const double inline_ms : {0.0, 1e9}) {
    SCOPED_TRACE(inline_ms);
    const SceneSource s = SceneSource::open(scene(R"({"frames": {"pattern": "frames/f_%d.obj", "first": 0, "count": 5}})"));
    FrameReadAhead reader(s, 1, 4, inline_ms);
    EXPECT_EQ(reader.next_index(), 1u);
    const Frame f1 = reader.next();
    const Frame f2 = reader.next();
    EXPECT_EQ(reader.next_index(), 3u);
    EXPECT_EQ(f1.index, 1);
    EXPECT_EQ(f2.index, 2);
    EXPECT_EQ(f1.objects[1].positions[0], Vec3(11, 0, 0));
    EXPECT_EQ(f2.objects[1].positions[0], Vec3(12, 0, 0));
    EXPECT_EQ(f1.objects[0].topology.get(), f2.objects[0].topology.get());
    EXPECT_EQ(f1.objects[1].topology.get(), f2.objects[1].topology.get());
    try {
      reader.next();
      ADD_FAILURE() << "frame 3 is malformed";
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("f_3.obj"), std::string::npos) << e.what();
    }

    // Given up on with a read still running, or with nothing left to read: no error.
    {
      FrameReadAhead unused(s, 0, 5, inline_ms);
      EXPECT_EQ(unused.next().index, 0);
    }
    { FrameReadAhead empty(s, 2, 2, inline_ms); }
    FrameReadAhead last(s, 4, 5, inline_ms);
    EXPECT_EQ(last.next().index, 4);
    EXPECT_EQ(last.next_index(), 5u);
  }
}

TEST_F(SceneSourceTest, FileListDefaultNameAndPercentInPattern) {
  dir.write("x.obj", triangles_obj({""}));
  dir.write("sub/y.obj", triangles_obj({""}, 1));
  const SceneSource s =
      SceneSource::open(scene(R"({"frames": {"files": ["x.obj", "sub/y.obj"]}})"));
  EXPECT_EQ(s.name(), "scene");  // the scene file's stem
  EXPECT_EQ(s.frame_count(), 2u);
  EXPECT_TRUE(s.queries().empty());
  EXPECT_FALSE(s.grid().has_value());
  const Frame f = s.load_frame(1);
  ASSERT_EQ(f.objects.size(), 1u);
  EXPECT_EQ(f.objects[0].name, "y");

  dir.write("p%_7.obj", triangles_obj({"t"}));
  const SceneSource p =
      SceneSource::open(scene(R"({"frames": {"pattern": "p%%_%i.obj", "first": 7, "count": 1}})"));
  EXPECT_EQ(p.load_frame(0).files[0], (dir.path() / "p%_7.obj").string());
}

TEST_F(SceneSourceTest, AbsolutePathsAndSharedTopologyOnThickCloth) {
  const fs::path data = fs::path(VPROXQ_TEST_DATA_DIR) / "meshes" / "thick-cloth";
  const SceneSource s =
      SceneSource::open(scene(R"({"frames": {"files": [")" + (data / "t0.ply").string() +
                              R"(", ")" + (data / "t1.ply").string() + R"("]}})"));
  const Frame f0 = s.load_frame(0);
  const Frame f1 = s.load_frame(1);
  ASSERT_EQ(f0.objects.size(), 1u);
  EXPECT_EQ(f0.objects[0].name, "t0");
  EXPECT_EQ(f0.objects[0].num_vertices(), 233);
  EXPECT_EQ(f0.objects[0].num_triangles(), 404);
  EXPECT_EQ(f0.objects[0].topology.get(), f1.objects[0].topology.get());
  EXPECT_NE(f0.objects[0].positions, f1.objects[0].positions);
}

TEST_F(SceneSourceTest, ChangedTopologyGetsANewObjectAndOldOnesAreReleased) {
  dir.write("a.obj", triangles_obj({"m"}));
  dir.write("b.obj", "o m\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 3 2\n");
  const SceneSource s = SceneSource::open(scene(R"({"frames": {"files": ["a.obj", "b.obj"]}})"));
  std::weak_ptr<const Topology> first;
  {
    const Frame f0 = s.load_frame(0);
    first = f0.objects[0].topology;
    const Frame f1 = s.load_frame(1);
    EXPECT_NE(f0.objects[0].topology.get(), f1.objects[0].topology.get());
    EXPECT_EQ(f1.objects[0].topology->faces, (std::vector<Face>{{0, 2, 1}}));
  }
  // Only the last frame's topologies are remembered: memory does not grow with frames.
  EXPECT_TRUE(first.expired());
}

TEST_F(SceneSourceTest, PerObjectSequencesMergeEachFileInFileOrder) {
  // Two groups and an isolated vertex: one object, every vertex in file order.
  for (int k = 0; k < 2; ++k) {
    dir.write("cloth_" + std::to_string(k) + ".obj",
              "v 0 0 " + std::to_string(k) +
                  "\nv 1 0 0\nv 0 1 0\nv 9 9 9\nv 2 0 0\nv 3 0 0\n"
                  "o left\nf 1 2 3\no right\nf 5 6 2\n");
    dir.write("ball" + std::to_string(k) + ".ply",
              "ply\nformat ascii 1.0\nelement vertex 3\nproperty double x\nproperty double y\n"
              "property double z\nelement face 1\nproperty list uchar int vertex_indices\n"
              "end_header\n0 0 5\n1 0 5\n0 1 5\n3 0 1 2\n");
  }
  const SceneSource s = SceneSource::open(scene(R"({"objects": [
      {"name": "cloth", "frames": {"pattern": "cloth_%d.obj", "count": 2}},
      {"name": "ball", "frames": {"files": ["ball0.ply", "ball1.ply"]}}]})"));
  EXPECT_EQ(s.frame_count(), 2u);
  const Frame f = s.load_frame(1);
  EXPECT_EQ(f.files.size(), 2u);
  ASSERT_EQ(f.objects.size(), 2u);
  EXPECT_EQ(f.objects[0].name, "cloth");
  EXPECT_EQ(f.objects[0].num_vertices(), 6);
  EXPECT_EQ(f.objects[0].positions[0], Vec3(0, 0, 1));
  EXPECT_EQ(f.objects[0].topology->faces, (std::vector<Face>{{0, 1, 2}, {4, 5, 1}}));
  EXPECT_EQ(f.objects[1].name, "ball");
  EXPECT_EQ(f.objects[1].num_triangles(), 1);
}

TEST_F(SceneSourceTest, StaticGeometryIsSharedByEveryFrame) {
  dir.write("f0.obj", triangles_obj({"mover"}, 0));
  dir.write("f1.obj", triangles_obj({"mover"}, 1));
  dir.write("bowl.obj", triangles_obj({"bowl", "rim"}, 100));
  dir.write("floor.obj", kCubeObj);
  const SceneSource s = SceneSource::open(
      scene(R"({"frames": {"files": ["f0.obj", "f1.obj"]}, "static": ["bowl.obj", "floor.obj"]})"));
  const Frame f0 = s.load_frame(0);
  const Frame f1 = s.load_frame(1);
  ASSERT_EQ(f0.objects.size(), 4u);
  EXPECT_EQ(f0.files.size(), 1u);
  EXPECT_EQ(f0.objects[0].name, "mover");
  EXPECT_FALSE(f0.objects[0].is_static);
  EXPECT_EQ(f0.objects[1].name, "bowl");
  EXPECT_EQ(f0.objects[2].name, "rim");
  EXPECT_EQ(f0.objects[3].name, "floor");
  EXPECT_EQ(f0.objects[3].num_triangles(), 12);
  for (std::size_t i = 1; i < 4; ++i) {
    EXPECT_TRUE(f0.objects[i].is_static);
    EXPECT_EQ(f0.objects[i].topology.get(), f1.objects[i].topology.get());
    EXPECT_EQ(f0.objects[i].positions, f1.objects[i].positions);
  }
}

TEST_F(SceneSourceTest, ComponentsSplitFramesAndStatics) {
  // A group of two separate triangles breaks into three pieces in the next frame.
  dir.write("c0.obj",
            "o pieces\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 5 0 0\nv 6 0 0\nv 5 1 0\n"
            "f 4 5 6\nf 1 2 3\n");
  dir.write("c1.obj", "o pieces\n" + triangles_obj({"", "", ""}));
  dir.write("walls.obj", "o walls\n" + triangles_obj({"", ""}, 100));
  const SceneSource s = SceneSource::open(scene(
      R"({"frames": {"files": ["c0.obj", "c1.obj"]}, "objects": "components", "static": ["walls.obj"]})"));
  EXPECT_EQ(s.split(), ObjectSplit::Components);
  const Frame f0 = s.load_frame(0);
  ASSERT_EQ(f0.objects.size(), 4u);
  EXPECT_EQ(f0.objects[0].name, "pieces#0");
  EXPECT_EQ(f0.objects[0].positions[0], Vec3(5, 0, 0));  // first face first
  EXPECT_EQ(f0.objects[1].name, "pieces#1");
  EXPECT_EQ(f0.objects[2].name, "walls#0");
  EXPECT_EQ(f0.objects[3].name, "walls#1");
  EXPECT_TRUE(f0.objects[3].is_static);
  const Frame f1 = s.load_frame(1);  // the count may change with "components"
  EXPECT_EQ(f1.objects.size(), 5u);
  EXPECT_EQ(f1.objects[2].name, "pieces#2");
}

TEST_F(SceneSourceTest, BareMeshFilesAreOneFrameScenes) {
  const SceneSource ply = SceneSource::open(fs::path(VPROXQ_TEST_DATA_DIR) / "meshes/cube.ply");
  EXPECT_EQ(ply.name(), "cube");
  EXPECT_EQ(ply.frame_count(), 1u);
  EXPECT_EQ(ply.split(), ObjectSplit::Meshes);
  const Frame f = ply.load_frame(0);
  ASSERT_EQ(f.objects.size(), 1u);
  EXPECT_EQ(f.objects[0].num_vertices(), 8);
  EXPECT_EQ(f.objects[0].num_triangles(), 12);

  const auto obj = dir.write("pair.obj", triangles_obj({"left", "right"}));
  const Frame g = SceneSource::open(obj).load_frame(0);
  ASSERT_EQ(g.objects.size(), 2u);
  EXPECT_EQ(g.objects[1].name, "right");

  const auto missing = dir.path() / "missing.obj";
  EXPECT_INPUT_ERROR(SceneSource::open(missing), missing.string() + ": file not found");
}

TEST_F(SceneSourceTest, FrameOutOfRangeIsAProgrammingError) {
  dir.write("a.obj", triangles_obj({"m"}));
  const SceneSource s = SceneSource::open(scene(R"({"frames": {"files": ["a.obj"]}})"));
  EXPECT_THROW(s.load_frame(1), std::out_of_range);
}

TEST_F(SceneSourceTest, MovedSceneSourceStillWorks) {
  dir.write("a.obj", triangles_obj({"m"}));
  SceneSource s = SceneSource::open(scene(R"({"frames": {"files": ["a.obj"]}})"));
  SceneSource t = std::move(s);
  EXPECT_EQ(t.load_frame(0).objects.size(), 1u);
}

// ---- frame errors: the message names the file ----

TEST_F(SceneSourceTest, ObjectCountMustMatchTheFirstFrameLoaded) {
  const auto a = dir.write("a.obj", triangles_obj({"x", "y"}));
  const auto b = dir.write("b.obj", triangles_obj({"x", "y", "z"}));
  const auto path = scene(R"({"frames": {"files": ["a.obj", "b.obj"]}})");
  {
    const SceneSource s = SceneSource::open(path);
    s.load_frame(0);
    EXPECT_INPUT_ERROR(s.load_frame(1), b.string() + ": frame 1 has 3 objects",
                       "frame 0 (" + a.string() + ", the first frame loaded) has 2");
  }
  {
    const SceneSource s = SceneSource::open(path);
    s.load_frame(1);
    EXPECT_INPUT_ERROR(s.load_frame(0), a.string() + ": frame 0 has 2 objects", "has 3");
  }
}

TEST_F(SceneSourceTest, EmptyAndBadFramesNameTheirFile) {
  const auto empty = dir.write("empty.obj", "v 0 0 0\nv 1 0 0\n");
  const auto nan = dir.write("nan.obj", "v 0 0 0\nv 1 0 0\nv 0 nan 0\nf 1 2 3\n");
  const auto range = dir.write("range.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n");
  const SceneSource s =
      SceneSource::open(scene(R"({"frames": {"files": ["empty.obj", "nan.obj", "range.obj"]}})"));
  EXPECT_INPUT_ERROR(s.load_frame(0), empty.string() + ": empty frame");
  EXPECT_INPUT_ERROR(s.load_frame(1), nan.string() + ": line 3: vertex 3 has a non-finite");
  EXPECT_INPUT_ERROR(s.load_frame(2), range.string() + ": line 3: face index 3 out of range");

  dir.write("ok.obj", triangles_obj({"m"}));
  const SceneSource per = SceneSource::open(scene(R"({"objects": [
      {"name": "a", "frames": {"files": ["ok.obj"]}},
      {"name": "b", "frames": {"files": ["empty.obj"]}}]})"));
  EXPECT_INPUT_ERROR(per.load_frame(0), empty.string() + ": no triangles (object \"b\"");
}

// ---- scene.json errors: the message names the scene file, the key and why ----

// Nesting far beyond a scene's few levels is refused while parsing (printing it in the
// message about the wrong type recursed that deep and overflowed the stack).
TEST_F(SceneSourceTest, DeeplyNestedJsonIsAnInputError) {
  const std::string deep = std::string(100000, '[') + std::string(100000, ']');
  for (const std::string& text : {deep, "{\"name\": " + deep + "}"}) {
    const auto path = scene(text);
    const std::string message = test::input_error_message([&] { SceneSource::open(path); });
    EXPECT_EQ(message.rfind(path.string() + ": invalid JSON: nested more than", 0), 0u) << message;
  }
}

struct BadScene {
  const char* json;
  std::vector<std::string> phrases;
};

TEST_F(SceneSourceTest, EveryBadKeyIsReported) {
  dir.write("a_0.obj", triangles_obj({"m"}));
  dir.write("a_1.obj", triangles_obj({"m"}));
  dir.write("cloud.obj", "v 0 0 0\n");
  dir.write("broken.obj", "v 0 0 0\nf 1 2 3\n");
  const std::vector<BadScene> cases = {
      {R"({"frames": )", {"invalid JSON"}},
      {R"([1, 2])", {"the scene must be a JSON object"}},
      {R"({"framse": {"files": ["a_0.obj"]}})",
       {"unknown key \"framse\"", "did you mean \"frames\"?"}},
      {R"({"frames": {"patern": "a_%d.obj", "count": 2}})",
       {"unknown key \"frames.patern\"", "did you mean \"frames.pattern\"?"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "qeuries": []})", {"unknown key \"qeuries\""}},
      {R"({"frames": {"files": ["a_0.obj"]}, "colour": "red"})",
       {"unknown key \"colour\"", "allowed top-level keys"}},
      {R"({"name": 3, "frames": {"files": ["a_0.obj"]}})",
       {"\"name\" must be a non-empty string, got 3"}},
      {R"({"name": ""})", {"\"name\" must be a non-empty string"}},
      {R"({"grid": 8})", {"\"frames\" is missing"}},
      {R"({"frames": ["a_0.obj"]})", {"\"frames\" must be an object"}},
      {R"({"frames": {"files": ["a_0.obj"], "pattern": "a_%d.obj"}})",
       {"\"frames.files\" cannot be combined with \"frames.pattern\""}},
      {R"({"frames": {"pattern": "a_%d.obj"}})",
       {"\"frames\" needs either \"pattern\" and \"count\""}},
      {R"({"frames": {"pattern": "a_%d.obj", "count": -3}})",
       {"scene.json: \"frames.count\" must be an integer from 1 to 2147483647, got -3"}},
      {R"({"frames": {"pattern": "a_%d.obj", "count": 0}})",
       {"\"frames.count\" must be an integer from 1 to 2147483647, got 0"}},
      {R"({"frames": {"pattern": "a_%d.obj", "count": 2.5}})",
       {"\"frames.count\" must be an integer from 1 to 2147483647, got 2.5"}},
      {R"({"frames": {"pattern": "a_%d.obj", "count": "2"}})",
       {"\"frames.count\" must be an integer from 1 to 2147483647, got \"2\""}},
      {R"({"frames": {"pattern": "a_%d.obj", "count": 1000000000000}})",
       {"\"frames.count\" must be an integer from 1 to 2147483647, got 1000000000000"}},
      {R"({"frames": {"pattern": "a_%d.obj", "count": 1, "first": 3000000000}})",
       {"\"frames.first\" must be an integer from 0 to 2147483647, got 3000000000"}},
      {R"({"frames": {"pattern": "a_%d.obj", "count": 1, "first": -1}})",
       {"\"frames.first\" must be an integer from 0 to 2147483647, got -1"}},
      {R"({"frames": {"pattern": "a_%d.obj", "count": 2147483647, "first": 5}})",
       {"\"frames.count\" is too large"}},
      {R"({"frames": {"pattern": "a_0.obj", "count": 1}})",
       {"\"frames.pattern\" has no integer conversion"}},
      {R"({"frames": {"pattern": "a_%d_%d.obj", "count": 1}})",
       {"\"frames.pattern\" has more than one conversion"}},
      {R"({"frames": {"pattern": "a_%s.obj", "count": 1}})",
       {"\"frames.pattern\" has the conversion \"%s\""}},
      {R"({"frames": {"pattern": "a_%ld.obj", "count": 1}})",
       {"\"frames.pattern\" has the conversion \"%l\""}},
      {R"({"frames": {"pattern": "a_%04", "count": 1}})",
       {"\"frames.pattern\" ends inside a conversion"}},
      {R"({"frames": {"pattern": "a_%0999d.obj", "count": 1}})",
       {"\"frames.pattern\" has a field width"}},
      {R"({"frames": {"pattern": 5, "count": 1}})",
       {"\"frames.pattern\" must be a non-empty string"}},
      {R"({"frames": {"pattern": "a_%d.obj", "count": 3}})",
       {"\"frames.pattern\" frame 2: file not found: ", "a_2.obj"}},
      {R"({"frames": {"files": []}})", {"\"frames.files\" must be a non-empty array"}},
      {R"({"frames": {"files": "a_0.obj"}})", {"\"frames.files\" must be a non-empty array"}},
      {R"({"frames": {"files": [3]}})", {"\"frames.files[0]\" must be a non-empty string, got 3"}},
      {R"({"frames": {"files": ["/dev/null"]}})", {"\"frames.files[0]\" frame 0: not a regular file: /dev/null"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "frames": {"files": ["a_1.obj"]}})",
       {"invalid JSON: the key \"frames\" appears twice in one object"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "objects": [{"a": 1, "b": {"a": 2}}, {"a": 3, "a": 4}]})",
       {"invalid JSON: the key \"a\" appears twice in one object"}},
      // A number beyond double's range is malformed JSON too (it was a runtime error, exit 4).
      {R"({"frames": {"files": ["a_0.obj"]}, "grid": 1e400})", {"invalid JSON: ", "number overflow", "1e400"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "unknown": -1e400})", {"invalid JSON: ", "number overflow"}},
      {R"({"frames": {"files": ["a_0.obj\u0000x"]}})",
       {"\"frames.files[0]\" must not contain a NUL character"}},
      {R"({"frames": {"files": ["a_0.obj", "b.obj"]}})",
       {"\"frames.files[1]\" frame 1: file not found: ", "b.obj"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "objects": "mesh"})",
       {"\"objects\" must be \"meshes\", \"components\" or", "got \"mesh\""}},
      {R"({"frames": {"files": ["a_0.obj"]}, "objects": []})", {"\"objects\" must be"}},
      {R"({"objects": [5]})", {"\"objects[0]\" must be an object"}},
      {R"({"objects": [{"frames": {"files": ["a_0.obj"]}}]})", {"\"objects[0].name\" is missing"}},
      {R"({"objects": [{"name": "a"}]})", {"\"objects[0].frames\" is missing"}},
      {R"({"objects": [{"name": "a", "frames": {"files": ["a_0.obj"]}, "static": true}]})",
       {"unknown key \"objects[0].static\""}},
      {R"({"objects": [{"name": "a", "frames": {"files": ["a_0.obj"], "count": 1}}]})",
       {"\"objects[0].frames.files\" cannot be combined with \"objects[0].frames.count\""}},
      {R"({"frames": {"files": ["a_0.obj"]}, "objects": [{"name": "a", "frames": {"files": ["a_0.obj"]}}]})",
       {"\"frames\" cannot be used together with per-object sequences"}},
      {R"({"objects": [{"name": "a", "frames": {"files": ["a_0.obj", "a_1.obj"]}},
                       {"name": "b", "frames": {"files": ["a_0.obj"]}}]})",
       {"\"objects[1].frames\" has 1 frames, but \"objects[0].frames\" has 2"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "static": "a_0.obj"})",
       {"\"static\" must be an array"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "static": [""]})",
       {"\"static[0]\" must be a non-empty string"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "static": ["a_0.obj", "gone.obj"]})",
       {"\"static[1]\" cannot be read: ", "gone.obj: file not found"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "static": ["cloud.obj"]})",
       {"\"static[0]\" has no triangles"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "static": ["broken.obj"]})",
       {"\"static[0]\" cannot be read: ", "broken.obj: line 2: face index 2 out of range"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "queries": "distance"})",
       {"\"queries\" must be an array"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "queries": ["distanse"]})",
       {"\"queries[0]\" must be one of \"distance\", \"ccd\", \"pd\", got \"distanse\""}},
      {R"({"frames": {"files": ["a_0.obj"]}, "queries": []})",
       {"\"queries\" is empty"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "queries": ["ccd", "pd", "ccd"]})",
       {"\"queries[2]\" lists \"ccd\" a second time"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "grid": 0})",
       {"\"grid\" must be an integer in [1, 4096], got 0"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "grid": -5})",
       {"\"grid\" must be an integer in [1, 4096], got -5"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "grid": 1.5})",
       {"\"grid\" must be an integer in [1, 4096], got 1.5"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "grid": "64"})",
       {"\"grid\" must be an integer in [1, 4096], got \"64\""}},
      {R"({"frames": {"files": ["a_0.obj"]}, "grid": 99999999999})",
       {"\"grid\" must be an integer in [1, 4096]"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "grid": 4097})",
       {"\"grid\" must be an integer in [1, 4096], got 4097"}},
      {R"({"frames": {"files": ["a_0.obj"]}, "self": "off"})",
       {"\"self\" must be true or false, got \"off\""}},
      {R"({"frames": {"files": ["a_0.obj"]}, "self": 0})",
       {"\"self\" must be true or false, got 0"}},
  };
  for (const BadScene& c : cases) {
    SCOPED_TRACE(c.json);
    const auto path = scene(c.json);
    const std::string message = test::input_error_message([&] { SceneSource::open(path); });
    if (std::getenv("VPROXQ_PRINT_MESSAGES") != nullptr) std::printf("%s\n", message.c_str());
    EXPECT_EQ(message.rfind(path.string() + ": ", 0), 0u) << message;
    for (const std::string& p : c.phrases) {
      EXPECT_NE(message.find(p), std::string::npos) << "message: " << message << "\n  lacks: " << p;
    }
  }
}

TEST_F(SceneSourceTest, MissingSceneFile) {
  const auto path = dir.path() / "nowhere" / "scene.json";
  EXPECT_INPUT_ERROR(SceneSource::open(path), path.string() + ": file not found");
}

}  // namespace
}  // namespace vproxq
