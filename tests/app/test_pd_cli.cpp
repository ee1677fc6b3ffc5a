// Discrete collisions and penetration depth end to end: the two-cubes meshes (split into
// objects by connected component) and the CLI's JSON and HDF5 output against the brute force.
#include "core/query/intersecting_pairs.hpp"
#include "core/query/penetration_depth.hpp"
#include "io/hdf5_reader.hpp"
#include "io/mesh_reader.hpp"
#include "io/scene_source.hpp"
#include "support/cli.hpp"
#include "support/pd_checks.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <fstream>
#include <map>

namespace vproxq {
namespace {

namespace fs = std::filesystem;
using test::quote;
using test::run_command;
using test::ScratchDir;

const fs::path kMeshes = fs::path(VPROXQ_TEST_DATA_DIR) / "meshes";
const char* const kTwoCubes[] = {"two-cubes-far.ply", "two-cubes-close.ply", "two-cubes-intersecting.ply"};

/// The rows of `group`/pd/inside_vertices and pd/overlapping_triangles are, in order, each
/// entry's features of side 0 then of side 1: {pair, objects[side], feature, side}.
void expect_pd_features(const Hdf5Reader& h5, const std::string& group, const std::vector<PenetrationDepth>& pd) {
  using Row = std::array<std::int64_t, 4>;
  for (const bool vertices : {true, false}) {
    const std::string ds = group + (vertices ? "/pd/inside_vertices" : "/pd/overlapping_triangles");
    SCOPED_TRACE(ds);
    std::vector<Row> expected;
    for (size_t p = 0; p < pd.size(); ++p)
      for (int side = 0; side < 2; ++side)
        for (Index f : vertices ? pd[p].inside_vertices[side] : pd[p].overlapping_triangles[side])
          expected.push_back({static_cast<std::int64_t>(p), pd[p].objects[side], f, side});
    const auto pair = h5.int_field(ds, "pair"), object = h5.int_field(ds, "object"),
               id = h5.int_field(ds, vertices ? "vertex" : "triangle"), side = h5.int_field(ds, "side");
    std::vector<Row> written;
    for (size_t r = 0; r < pair.size(); ++r) written.push_back({pair[r], object[r], id[r], side[r]});
    EXPECT_EQ(written, expected);
  }
}

/// One frame with one object per connected component of the file.
Frame load_components(const fs::path& file) {
  Frame frame;
  for (const MeshGroup& g : read_mesh_file(file))
    for (MeshGroup& c : split_components(g)) {
      Object o;
      o.name = c.name;
      auto topo = std::make_shared<Topology>();
      topo->num_vertices = static_cast<Index>(c.positions.size());
      topo->faces = std::move(c.faces);
      o.topology = topo;
      o.positions = std::move(c.positions);
      frame.objects.push_back(std::move(o));
    }
  return frame;
}

TEST(PdTwoCubes, IntersectingHasDepthCloseAndFarHaveNoPairs) {
  for (const char* name : kTwoCubes) {
    SCOPED_TRACE(name);
    const Frame frame = load_components(kMeshes / name);
    ASSERT_EQ(frame.objects.size(), 2u);
    const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
    const auto got = intersecting_pairs(frame, boxes, {2, nullptr, true});
    const auto ref = intersecting_pairs_brute_force(frame);
    EXPECT_EQ(got.pairs, ref.pairs);
    const auto pd = penetration_depth(frame, boxes, got.pairs, {2}).pairs;
    if (std::string(name) == "two-cubes-intersecting.ply") {
      ASSERT_FALSE(got.pairs.empty());
      ASSERT_EQ(pd.size(), 1u);
      EXPECT_EQ(pd[0].status, PdStatus::Ok) << pd_status_name(pd[0].status);
      EXPECT_GT(pd[0].depth, 0.0);
      EXPECT_NEAR(pd[0].direction.norm(), 1.0, 1e-12);
      std::printf("[ two-cubes ] %zu intersecting pairs, depth %.17g, direction (%.6g, %.6g, %.6g)\n",
                  got.pairs.size(), pd[0].depth, pd[0].direction.x(), pd[0].direction.y(), pd[0].direction.z());
    } else {
      EXPECT_TRUE(got.pairs.empty());
      EXPECT_TRUE(pd.empty());
    }
  }
}

TEST(PdTwoCubes, CliWritesPairsAndDepth) {
  ScratchDir dir;
  for (const char* name : kTwoCubes) fs::copy_file(kMeshes / name, dir / name);
  const auto scene = dir.write("scene.json", R"({"name": "two-cubes", "objects": "components",
    "frames": {"files": ["two-cubes-far.ply", "two-cubes-close.ply", "two-cubes-intersecting.ply"]}})");
  const auto r = test::vproxq(quote(scene) +
                             " --queries=distance,pd --threads 2 --quiet -o " + quote(dir / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = test::read_json(dir / "out" / "results.json");
  EXPECT_EQ(j["queries"], nlohmann::json::array({"distance", "pd"}));
  const SceneSource source = SceneSource::open(scene);
  Hdf5Reader h5(dir / "out" / "results.h5");
  ASSERT_EQ(j["frames"].size(), 3u);
  for (size_t k = 0; k < 3; ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    const Frame frame = source.load_frame(k);
    const auto ref = intersecting_pairs_brute_force(frame);
    const auto& fj = j["frames"][k];
    EXPECT_EQ(fj["distance"]["intersecting_pairs"].get<size_t>(), ref.pairs.size());
    const std::string group = "/frames/00000" + std::to_string(k);
    const std::string ds = group + "/intersecting_pairs";
    ASSERT_EQ(h5.rows(ds), ref.pairs.size());
    const auto oa = h5.int_field(ds, "object_a"), ta = h5.int_field(ds, "tri_a");
    const auto ob = h5.int_field(ds, "object_b"), tb = h5.int_field(ds, "tri_b");
    for (size_t p = 0; p < ref.pairs.size(); ++p)
      EXPECT_EQ((IntersectingPair{static_cast<Index>(oa[p]), static_cast<Index>(ta[p]),
                                  static_cast<Index>(ob[p]), static_cast<Index>(tb[p])}),
                ref.pairs[p]);
    const auto pd = penetration_depth(frame, FrameBoxes::compute(frame, 1), ref.pairs, {1}).pairs;
    ASSERT_EQ(fj["pd"].size(), pd.size());
    ASSERT_EQ(h5.rows(group + "/pd/pairs"), pd.size());
    for (size_t p = 0; p < pd.size(); ++p) {
      EXPECT_EQ(fj["pd"][p]["objects"], nlohmann::json::array({pd[p].objects[0], pd[p].objects[1]}));
      ASSERT_EQ(pd[p].status, PdStatus::Ok);
      EXPECT_FALSE(fj["pd"][p].contains("status"));
      EXPECT_EQ(fj["pd"][p]["depth"].get<double>(), pd[p].depth);
      EXPECT_GT(pd[p].depth, 0.0);
      for (int c = 0; c < 3; ++c) EXPECT_EQ(fj["pd"][p]["direction"][c].get<double>(), pd[p].direction[c]);
      EXPECT_EQ(h5.double_field(group + "/pd/pairs", "depth")[p], pd[p].depth);
      EXPECT_EQ(h5.int_field(group + "/pd/pairs", "status")[p], 0);
    }
    expect_pd_features(h5, group, pd);
  }
}

TEST(PdSelf, CliWritesTheReasonOfEachSelfIntersectionEntry) {
  // Soft letters in a bowl whose "g" folds through itself (tests/data/folded-letters, the tiny
  // bowl scene as the generator wrote it up to a00fc26): its self entries with and without a
  // number. Each entry of the JSON and HDF5 output is the core's for the frame, with "reason"
  // (and HDF5's reason, reason_a, reason_b) on self_intersection entries only, and each reason
  // holds (tests/support/pd_checks.hpp).
  ScratchDir dir;
  const fs::path scene = fs::path(VPROXQ_TEST_DATA_DIR) / "folded-letters" / "scene.json";
  const auto r = test::vproxq(quote(scene) + " --queries=pd --threads 2 --quiet -o " + quote(dir / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = test::read_json(dir / "out" / "results.json");
  Hdf5Reader h5(dir / "out" / "results.h5");
  const SceneSource source = SceneSource::open(scene);
  std::map<std::string, int> seen;
  for (size_t k = 0; k < j["frames"].size(); ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    const Frame frame = source.load_frame(k);
    const auto pairs = intersecting_pairs_brute_force(frame).pairs;
    const auto pd = penetration_depth(frame, FrameBoxes::compute(frame, 1), pairs, {1}).pairs;
    const auto& fj = j["frames"][k]["pd"];
    ASSERT_EQ(fj.size(), pd.size());
    const std::string ds = "/frames/00000" + std::to_string(k) + "/pd/pairs";
    ASSERT_EQ(h5.rows(ds), pd.size());
    const auto reason = h5.int_field(ds, "reason"), ra = h5.int_field(ds, "reason_a"), rb = h5.int_field(ds, "reason_b");
    for (size_t p = 0; p < pd.size(); ++p) {
      test::expect_reason_holds(frame, pd[p], pairs);
      const bool undecided = pd[p].status == PdStatus::SelfIntersection;
      EXPECT_EQ(fj[p].contains("reason"), undecided);
      if (undecided) {
        EXPECT_EQ(fj[p]["reason"], pd_reason_name(pd[p].reason));
      }
      EXPECT_EQ(reason[p], static_cast<int>(pd[p].reason));
      EXPECT_EQ(ra[p], pd[p].reason_features[0]);
      EXPECT_EQ(rb[p], pd[p].reason_features[1]);
      ++seen[undecided ? pd_reason_name(pd[p].reason) : pd_status_name(pd[p].status)];
    }
    // A self entry's two lists, one object's, told apart by `side` only.
    expect_pd_features(h5, "/frames/00000" + std::to_string(k), pd);
  }
  // What the scene holds (docs/algorithms.md, "Where it gives no number"): a number on three frames, one
  // pair of sheets the curve does not separate; the independent PD oracle (written from the
  // docs/algorithms.md, exact rationals) predicts the same entries, frame 0's at triangles 48 and 53.
  EXPECT_EQ(seen, (std::map<std::string, int>{{"ok", 3}, {"sheets_not_separated", 1}}));
  // The terminal summary names the reason and where.
  const auto summary = test::vproxq(quote(scene) + " --queries=pd --threads 2 --frames 0:1");
  ASSERT_EQ(summary.exit_code, 0) << summary.output;
  const Frame frame = source.load_frame(0);
  const auto pd = penetration_depth(frame, FrameBoxes::compute(frame, 1), intersecting_pairs_brute_force(frame).pairs, {1}).pairs;
  ASSERT_EQ(pd.size(), 1u);
  const std::string line = "pd " + std::to_string(pd[0].objects[0]) + "-" + std::to_string(pd[0].objects[1]) +
                           ": self_intersection (sheets_not_separated: triangles " + std::to_string(pd[0].reason_features[0]) +
                           " and " + std::to_string(pd[0].reason_features[1]) + ")\n";
  EXPECT_NE(summary.output.find(line), std::string::npos) << line << summary.output;
}

TEST(PdTwoCubes, CliReportsStatusInsteadOfNumber) {
  // An open surface (one face of the second box missing) intersecting a box: status, nulls.
  ScratchDir dir;
  std::string obj;
  auto box = [&](double x0, int base, bool drop_last) {
    for (int k = 0; k < 8; ++k)
      obj += "v " + std::to_string(x0 + (k & 1)) + " " + std::to_string((k >> 1) & 1) + " " + std::to_string((k >> 2) & 1) + "\n";
    const int q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (int f = 0; f < (drop_last ? 5 : 6); ++f)
      obj += "f " + std::to_string(base + q[f][0]) + " " + std::to_string(base + q[f][1]) + " " +
             std::to_string(base + q[f][2]) + " " + std::to_string(base + q[f][3]) + "\n";
  };
  obj += "o closed\n";
  box(0.0, 1, false);
  obj += "o open\n";
  box(0.5, 9, true);
  const auto file = dir.write("boxes.obj", obj);
  const auto r = test::vproxq(quote(file) + " --queries=pd --quiet -o " + quote(dir / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const nlohmann::json j = test::read_json(dir / "out" / "results.json");
  const auto& fj = j["frames"][0];
  EXPECT_FALSE(fj.contains("distance"));
  ASSERT_EQ(fj["pd"].size(), 1u);
  EXPECT_EQ(fj["pd"][0]["status"], "open_surface");
  EXPECT_TRUE(fj["pd"][0]["depth"].is_null());
  EXPECT_TRUE(fj["pd"][0]["direction"].is_null());
}

}  // namespace
}  // namespace vproxq
