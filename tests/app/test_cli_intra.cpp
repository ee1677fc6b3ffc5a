// End-to-end: the CLI's distance.intra (JSON) and distance/intra (HDF5) equal the library's
// brute force, with every Stage II backend.
#include "core/query/intersecting_pairs.hpp"
#include "core/query/intra_distance.hpp"
#include "core/voronoi/self_stage2.hpp"
#include "io/hdf5_reader.hpp"
#include "io/scene_source.hpp"
#include "support/cli.hpp"
#include "support/self_meshes.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cstdio>
#include <fstream>

namespace vproxq {
namespace {

namespace fs = std::filesystem;
using test::quote;
using test::run_command;
using test::ScratchDir;
using test::read_json;
using test::vproxq;


/// The JSON distance.intra of a frame (one entry per object: its minimum) equals `ref`.
void expect_intra_json(const nlohmann::json& intra, const IntraDistanceOutput& ref) {
  ASSERT_EQ(intra.size(), ref.per_object.size());
  for (size_t i = 0; i < ref.per_object.size(); ++i) {
    const auto& e = ref.per_object[i];
    EXPECT_EQ(intra[i]["object"].get<int>(), static_cast<int>(i));
    if (!e.has_pair()) {
      EXPECT_TRUE(intra[i]["distance"].is_null());
      EXPECT_TRUE(intra[i]["triangles"].is_null());
      continue;
    }
    EXPECT_EQ(intra[i]["distance"].get<double>(), e.distance);
    EXPECT_EQ(intra[i]["triangles"][0].get<int>(), e.triangles[0]);
    EXPECT_EQ(intra[i]["triangles"][1].get<int>(), e.triangles[1]);
    for (int c = 0; c < 3; ++c) {
      EXPECT_EQ(intra[i]["points"][0][c].get<double>(), e.points[0][c]);
      EXPECT_EQ(intra[i]["points"][1][c].get<double>(), e.points[1][c]);
    }
  }
}

/// The HDF5 per-triangle table `table` (object-major) equals `ref`.
void expect_intra_table(const Hdf5Reader& h5, const std::string& table, const IntraDistanceOutput& ref) {
  const auto object = h5.int_field(table, "object");
  const auto triangle = h5.int_field(table, "triangle");
  const auto nearest = h5.int_field(table, "nearest");
  const auto distance = h5.double_field(table, "distance");
  const auto point_a = h5.double_field(table, "point_a");
  size_t row = 0;
  for (size_t i = 0; i < ref.per_object.size(); ++i)
    for (size_t t = 0; t < ref.per_object[i].per_triangle.size(); ++t, ++row) {
      ASSERT_LT(row, object.size());
      const auto& e = ref.per_object[i].per_triangle[t];
      EXPECT_EQ(object[row], static_cast<std::int64_t>(i));
      EXPECT_EQ(triangle[row], static_cast<std::int64_t>(t));
      EXPECT_EQ(nearest[row], e.nearest);
      EXPECT_EQ(distance[row], e.distance);
      if (e.nearest == kNoIndex) continue;
      for (int c = 0; c < 3; ++c) EXPECT_EQ(point_a[3 * row + static_cast<size_t>(c)], e.points[0][c]);
    }
  EXPECT_EQ(row, object.size());
}

TEST(CliIntra, JsonAndHdf5EqualBruteForceWithEveryBackend) {
  ScratchDir dir;
  test::Rng rng(3);
  Frame made;
  made.objects.push_back(test::make_folded_sheet(rng, 12, 5, 0.1, 0.04, 0.1, "sheet"));
  made.objects.push_back(test::make_blob(rng, Vec3(2, 0, 0), 0.8, 1, 0.5, "blob"));
  made.objects.push_back(test::make_object({{5, 0, 0}, {6, 0, 0}, {5, 1, 0}}, {{0, 1, 2}}, "single"));
  made.objects.push_back(test::make_tetrahedra(1, 0, "tetrahedron"));
  test::write_obj(made, dir / "scene.obj");
  // What the CLI will see: the OBJ read back (its own double parsing), not `made`.
  const Frame frame = SceneSource::open(dir / "scene.obj").load_frame(0);
  const auto ref = intra_object_distance_brute_force(frame);
  for (const char* backend : {"off", "cpu", "gpu"}) {
    SCOPED_TRACE(backend);
    const fs::path out = dir / backend;
    const auto r = test::vproxq(quote(dir / "scene.obj") + " -o " +
                               quote(out) + " --quiet --threads 2 --voronoi=" + backend);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json j = test::read_json(out / "results.json");
    expect_intra_json(j["frames"][0]["distance"]["intra"], ref);
    EXPECT_GT(j["frames"][0]["stats"]["intra_exact_tests"].get<std::uint64_t>(), 0u);
    EXPECT_EQ(j["frames"][0]["stats"].contains("self_voronoi"), std::string(backend) != "off");
    if (std::string(backend) != "off") {
      // Sampled: the triangles of objects with pairs whose 2-ring bound exceeds 2δ and that
      // have a non-adjacent triangle (not the tetrahedron's).
      const auto& sv = j["frames"][0]["stats"]["self_voronoi"];
      const double delta = sv["delta"].get<double>();
      const auto ring2 = ring2_upper_bounds(frame, 1);
      std::uint64_t want = 0;
      for (size_t i = 0; i < ring2.size(); ++i)
        if (ring2[i].size() >= 2)
          for (size_t t = 0; t < ring2[i].size(); ++t)
            want += ring2[i][t] > kSelfSampleRing2OverDelta * delta && test::has_non_adjacent(frame.objects[i], static_cast<Index>(t));
      EXPECT_EQ(sv["sampled_triangles"].get<std::uint64_t>(), want);
      // The inter-object stage's: at most every triangle of the frame; the backends get the
      // sampled triangles (and those a sample can reach), at most all.
      std::uint64_t triangles = 0;
      for (const Object& o : frame.objects) triangles += static_cast<std::uint64_t>(o.num_triangles());
      EXPECT_LE(j["frames"][0]["stats"]["voronoi"]["sampled_triangles"].get<std::uint64_t>(), triangles);
      EXPECT_LE(j["frames"][0]["stats"]["voronoi"]["backend_triangles"].get<std::uint64_t>(), triangles);
      EXPECT_GE(sv["backend_triangles"].get<std::uint64_t>(), want);
      EXPECT_LE(sv["backend_triangles"].get<std::uint64_t>(), triangles);
    }

    // HDF5: the per-triangle table, object-major.
    const Hdf5Reader h5(out / "results.h5");
    expect_intra_table(h5, "/frames/000000/distance/intra", ref);
    EXPECT_EQ(h5.rows("/frames/000000/distance/intra_min"), ref.per_object.size());
  }
}

// Static geometry (scene "static") is the same in every frame: its intra-object results are
// computed on the first frame of a run and reused. On every frame they still equal the brute
// force, also where the static objects' ids shift (a piece breaks off a moving object, with
// "objects": "components"), and a later frame runs fewer exact tests than the same frame run
// alone.
TEST(CliIntra, StaticObjectsAreComputedOnceAndEqualBruteForceOnEveryFrame) {
  ScratchDir dir;
  test::Rng rng(11);
  Frame statics;
  statics.objects.push_back(test::make_folded_sheet(rng, 10, 4, 0.1, 0.05, 0.1, "sheet"));
  statics.objects.push_back(test::make_blob(rng, Vec3(3, 0, 0), 0.6, 1, 0.3, "rock"));
  test::write_obj(statics, dir / "static.obj");
  // Frame 0: one moving blob; frames 1 and 2: it moved and a second piece is there (so the
  // static objects come after two moving ones).
  for (int k = 0; k < 3; ++k) {
    Frame f;
    f.objects.push_back(test::make_blob(rng, Vec3(0.2 * k, 1.5, 0), 0.5, 1, 0.4, "mover"));
    if (k > 0) f.objects.push_back(test::make_blob(rng, Vec3(1.5, 1.5 + 0.1 * k, 0), 0.3, 1, 0.4, "mover"));
    test::write_obj(f, dir / ("frame_" + std::to_string(k) + ".obj"));
  }
  const auto scene = dir.write("scene.json", R"({"frames": {"pattern": "frame_%d.obj", "first": 0, "count": 3},
    "objects": "components", "static": ["static.obj"]})");
  const SceneSource source = SceneSource::open(scene);
  for (const char* backend : {"off", "cpu", "gpu"}) {
    SCOPED_TRACE(backend);
    const fs::path out = dir / backend;
    auto r = test::vproxq(quote(scene) + " -o " + quote(out) + " --quiet --threads 2 --queries=distance --voronoi=" + backend);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json j = test::read_json(out / "results.json");
    const Hdf5Reader h5(out / "results.h5");
    for (std::size_t k = 0; k < 3; ++k) {
      SCOPED_TRACE("frame " + std::to_string(k));
      const Frame frame = source.load_frame(k);
      ASSERT_EQ(frame.objects.size(), k == 0 ? 3u : 4u);
      ASSERT_TRUE(frame.objects.back().is_static);
      const auto ref = intra_object_distance_brute_force(frame);
      for (const auto& e : ref.per_object) ASSERT_TRUE(e.has_pair());
      expect_intra_json(j["frames"][k]["distance"]["intra"], ref);
      char group[64];
      std::snprintf(group, sizeof group, "/frames/%06zu/distance/intra", k);
      expect_intra_table(h5, group, ref);
    }
    // Frame 2 run alone computes the static objects too.
    r = test::vproxq(quote(scene) + " -o " + quote(dir / "alone") + " --quiet --threads 2 --queries=distance --frames 2:3 --voronoi=" + backend);
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const nlohmann::json alone = test::read_json(dir / "alone" / "results.json");
    EXPECT_LT(j["frames"][2]["stats"]["intra_exact_tests"].get<std::uint64_t>(),
              alone["frames"][0]["stats"]["intra_exact_tests"].get<std::uint64_t>());
    EXPECT_EQ(j["frames"][2]["distance"]["intra"], alone["frames"][0]["distance"]["intra"]);
  }
}

TEST(CliIntra, SelfOffLeavesOutTheIntraObjectPartAlone) {
  // --self off: the distance query without its intra-object part. The folded letters
  // (tests/data/folded-letters: soft letters in a bowl, one folding through itself) have pairs
  // of intersecting triangles within one object and self PD entries: they must still be found
  // (by the intersecting-pair search instead of the intra-object one), every other answer must
  // be the full run's, and nothing of the intra-object part may be written.
  ScratchDir dir;
  const fs::path scene = fs::path(VPROXQ_TEST_DATA_DIR) / "folded-letters" / "scene.json";
  const std::string common = quote(scene) + " --queries=distance,pd --threads 2 --quiet -o ";
  const auto on = vproxq(common + quote(dir / "on"));
  ASSERT_EQ(on.exit_code, 0) << on.output;
  const auto off = vproxq(common + quote(dir / "off") + " --self off");
  ASSERT_EQ(off.exit_code, 0) << off.output;
  const auto same = vproxq("diff --ignore intra " + quote(dir / "on" / "results.json") + " " + quote(dir / "off" / "results.json"));
  EXPECT_EQ(same.exit_code, 0) << same.output;
  const auto differs = vproxq("diff " + quote(dir / "on" / "results.json") + " " + quote(dir / "off" / "results.json"));
  EXPECT_EQ(differs.exit_code, 1) << differs.output;  // only through distance.intra

  const nlohmann::json j = read_json(dir / "off" / "results.json");
  EXPECT_EQ(j["settings"]["self"], false);
  EXPECT_EQ(read_json(dir / "on" / "results.json")["settings"]["self"], true);
  Hdf5Reader h5(dir / "off" / "results.h5");
  EXPECT_EQ(h5.int_attribute("/", "self"), 0);
  const SceneSource source = SceneSource::open(scene);
  size_t within_objects = 0;
  for (size_t k = 0; k < j["frames"].size(); ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    const nlohmann::json& f = j["frames"][k];
    EXPECT_FALSE(f["distance"].contains("intra"));
    EXPECT_TRUE(f["distance"].contains("inter"));
    EXPECT_FALSE(f["stats"].contains("intra_exact_tests"));
    EXPECT_FALSE(f["stats"]["time_ms"].contains("intra_exact"));
    const std::string g = "/frames/00000" + std::to_string(k);
    EXPECT_FALSE(h5.exists(g + "/distance/intra"));
    EXPECT_FALSE(h5.exists(g + "/distance/intra_min"));
    EXPECT_TRUE(h5.exists(g + "/distance/inter"));
    // Every intersecting pair, within objects too: the brute force's list, row by row.
    const auto pairs = intersecting_pairs_brute_force(source.load_frame(k)).pairs;
    const std::string ds = g + "/intersecting_pairs";
    ASSERT_EQ(h5.rows(ds), pairs.size());
    EXPECT_EQ(f["distance"]["intersecting_pairs"].get<size_t>(), pairs.size());
    const auto oa = h5.int_field(ds, "object_a"), ta = h5.int_field(ds, "tri_a");
    const auto ob = h5.int_field(ds, "object_b"), tb = h5.int_field(ds, "tri_b");
    std::vector<IntersectingPair> written;
    for (size_t r = 0; r < pairs.size(); ++r)
      written.push_back({static_cast<Index>(oa[r]), static_cast<Index>(ta[r]), static_cast<Index>(ob[r]), static_cast<Index>(tb[r])});
    std::sort(written.begin(), written.end());
    EXPECT_EQ(written, pairs);
    for (const IntersectingPair& p : pairs) within_objects += p.object_a == p.object_b;
  }
  EXPECT_GT(within_objects, 0u);  // the scene does test the pairs within objects

  // The scene's "self": false does the same, and --self on overrides it.
  fs::copy(scene.parent_path(), dir / "own", fs::copy_options::recursive);
  const fs::path own = dir / "own" / "scene.json";
  nlohmann::json scene_json = read_json(own);
  scene_json["self"] = false;
  std::ofstream(own) << scene_json.dump();
  const auto by_scene = vproxq(quote(own) + " --queries=distance,pd --threads 2 --quiet -o " + quote(dir / "by_scene"));
  ASSERT_EQ(by_scene.exit_code, 0) << by_scene.output;
  EXPECT_EQ(read_json(dir / "by_scene" / "results.json")["settings"]["self"], false);
  const auto as_off = vproxq("diff " + quote(dir / "off" / "results.json") + " " + quote(dir / "by_scene" / "results.json"));
  EXPECT_EQ(as_off.exit_code, 0) << as_off.output;
  const auto forced = vproxq(quote(own) + " --queries=distance,pd --threads 2 --quiet --self on -o " + quote(dir / "forced"));
  ASSERT_EQ(forced.exit_code, 0) << forced.output;
  const auto as_on = vproxq("diff " + quote(dir / "on" / "results.json") + " " + quote(dir / "forced" / "results.json"));
  EXPECT_EQ(as_on.exit_code, 0) << as_on.output;

  // Without the distance query the option changes nothing, and says so; a bad value is a
  // usage error.
  const auto note = vproxq(quote(scene) + " --queries=pd --frames 0:1 --self off");
  EXPECT_EQ(note.exit_code, 0) << note.output;
  EXPECT_NE(note.output.find("--self has no effect without the distance query"), std::string::npos) << note.output;
  const auto note_on = vproxq(quote(scene) + " --queries=pd --frames 0:1 --self on");
  EXPECT_EQ(note_on.exit_code, 0) << note_on.output;
  EXPECT_NE(note_on.output.find("--self has no effect without the distance query"), std::string::npos) << note_on.output;
  const auto bad = vproxq(quote(scene) + " --self maybe -o " + quote(dir / "bad"));
  EXPECT_EQ(bad.exit_code, 2) << bad.output;
  EXPECT_FALSE(fs::exists(dir / "bad"));
}

}  // namespace
}  // namespace vproxq
