// End-to-end CCD through the CLI: `--queries=ccd` on small seeded multi-frame scenes gives the
// brute force's answers (all primitive pairs, elementary tests) in results.json and
// results.h5, identical with --voronoi=off, cpu and gpu; the last frame has no ccd block;
// an object whose topology changes is listed in ccd.skipped.
#include "core/query/ccd.hpp"
#include "io/hdf5_reader.hpp"
#include "io/scene_source.hpp"
#include "support/cli.hpp"
#include "support/random_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

namespace vproxq {
namespace {

namespace fs = std::filesystem;
using test::quote;
using test::ScratchDir;
using test::read_json;
using test::vproxq;
using test::write_obj;

/// Frame `prev` with every object drifted and its vertices jittered (same topologies).
Frame moved(const Frame& prev, test::Rng& rng, double drift, double jitter) {
  Frame f = prev;
  for (Object& o : f.objects) {
    const Vec3 d = rng.vec3(-drift, drift);
    for (Vec3& p : o.positions) p += d + rng.vec3(-jitter, jitter);
  }
  return f;
}

/// A scene of `frames` frames of `n` moving blobs; returns the scene.json path.
fs::path write_scene(const ScratchDir& dir, std::uint64_t seed, int n, int frames) {
  test::Rng rng(seed * 7 + 1);
  Frame f = test::make_random_frame(seed, n, 2.5, 1);
  for (int k = 0; k < frames; ++k) {
    write_obj(f, dir / ("f_" + std::to_string(k) + ".obj"));
    f = moved(f, rng, 0.5, k % 2 ? 0.2 : 0.05);
  }
  return dir.write("scene.json", R"({"frames": {"pattern": "f_%d.obj", "first": 0, "count": )" +
                                     std::to_string(frames) + R"(}, "queries": ["ccd"]})");
}

/// Every frame's ccd block (JSON) and ccd/vf, ccd/ee (HDF5) equal the brute force.
void expect_equal_brute_force(const fs::path& scene_path, const fs::path& out, std::uint64_t& found) {
  const SceneSource scene = SceneSource::open(scene_path);
  const auto j = read_json(out / "results.json");
  const Hdf5Reader h5(out / "results.h5");
  const size_t n = scene.frame_count();
  ASSERT_EQ(j["frames"].size(), n);
  for (size_t k = 0; k < n; ++k) {
    SCOPED_TRACE("frame " + std::to_string(k));
    const auto& fj = j["frames"][k];
    char group[64];
    std::snprintf(group, sizeof group, "/frames/%06zu/ccd", k);
    if (k + 1 == n) {
      EXPECT_FALSE(fj.contains("ccd"));  // the last frame has no next frame
      EXPECT_FALSE(h5.exists(group));
      continue;
    }
    const CcdStepResult ref = continuous_collisions_brute_force(scene.load_frame(k), scene.load_frame(k + 1));
    found += ref.vf.size() + ref.ee.size();
    ASSERT_TRUE(fj.contains("ccd"));
    EXPECT_EQ(fj["ccd"]["to_frame"].get<int>(), static_cast<int>(k + 1));
    EXPECT_TRUE(fj["ccd"]["skipped"].empty());
    const auto& pairs = fj["ccd"]["pairs"];
    ASSERT_EQ(pairs.size(), ref.pairs.size());
    for (size_t p = 0; p < ref.pairs.size(); ++p) {
      EXPECT_EQ(pairs[p]["objects"][0].get<int>(), ref.pairs[p].objects[0]);
      EXPECT_EQ(pairs[p]["objects"][1].get<int>(), ref.pairs[p].objects[1]);
      EXPECT_EQ(pairs[p]["toi"].get<double>(), ref.pairs[p].toi);
      EXPECT_EQ(pairs[p]["primitive_pairs"].get<std::uint64_t>(), ref.pairs[p].primitive_pairs);
    }
    const std::string g = group;
    ASSERT_EQ(h5.rows(g + "/vf"), ref.vf.size());
    const auto ov = h5.int_field(g + "/vf", "object_v"), v = h5.int_field(g + "/vf", "vertex");
    const auto of = h5.int_field(g + "/vf", "object_f"), f = h5.int_field(g + "/vf", "face");
    const auto vt = h5.double_field(g + "/vf", "toi");
    for (size_t r = 0; r < ref.vf.size(); ++r) {
      EXPECT_EQ(ov[r], ref.vf[r].object_v);
      EXPECT_EQ(v[r], ref.vf[r].vertex);
      EXPECT_EQ(of[r], ref.vf[r].object_f);
      EXPECT_EQ(f[r], ref.vf[r].face);
      EXPECT_EQ(vt[r], ref.vf[r].toi);
    }
    ASSERT_EQ(h5.rows(g + "/ee"), ref.ee.size());
    const auto oa = h5.int_field(g + "/ee", "object_a"), a0 = h5.int_field(g + "/ee", "a0");
    const auto a1 = h5.int_field(g + "/ee", "a1"), ob = h5.int_field(g + "/ee", "object_b");
    const auto b0 = h5.int_field(g + "/ee", "b0"), b1 = h5.int_field(g + "/ee", "b1");
    const auto et = h5.double_field(g + "/ee", "toi");
    for (size_t r = 0; r < ref.ee.size(); ++r) {
      EXPECT_EQ(oa[r], ref.ee[r].object_a);
      EXPECT_EQ(a0[r], ref.ee[r].edge_a[0]);
      EXPECT_EQ(a1[r], ref.ee[r].edge_a[1]);
      EXPECT_EQ(ob[r], ref.ee[r].object_b);
      EXPECT_EQ(b0[r], ref.ee[r].edge_b[0]);
      EXPECT_EQ(b1[r], ref.ee[r].edge_b[1]);
      EXPECT_EQ(et[r], ref.ee[r].toi);
    }
    EXPECT_EQ(h5.uint_attribute(g, "elementary_tests"),
              fj["stats"]["ccd"]["elementary_tests"].get<std::uint64_t>());
  }
}

TEST(CcdCli, BackendsGiveIdenticalResultsEqualToBruteForce) {
  std::uint64_t found = 0;
  // Elementary tests with and without Stage II, summed over the seeds: Stage II culls only
  // candidate pairs whose swept triangles share no voxel, and about half of these small scenes
  // have none (seed 3: 228 tests either way); seeds 5 and 8 have some (220 of 225, 796 of 798).
  std::uint64_t all_tests_off = 0, all_tests_cpu = 0;
  for (std::uint64_t seed : {5u, 8u}) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    ScratchDir dir;
    const fs::path scene = write_scene(dir, seed, 4, 3);
    for (const char* backend : {"off", "cpu", "gpu"}) {
      SCOPED_TRACE(backend);
      const auto out = dir / backend;
      const auto r = vproxq(quote(scene) + " -o " + quote(out) + " --quiet --threads 2 --ccd-grid 24 --voronoi=" + backend);
      ASSERT_EQ(r.exit_code, 0) << r.output;
      expect_equal_brute_force(scene, out, found);
    }
    for (const char* backend : {"cpu", "gpu"}) {
      const auto r = vproxq("diff " + quote(dir / "off" / "results.json") + " " + quote(dir / backend / "results.json"));
      EXPECT_EQ(r.exit_code, 0) << backend << ": " << r.output;
    }
    // The GL Stage II does integer work only: the same culling as the CPU's, counter for
    // counter, and over the seeds it must cull something.
    const auto off = read_json(dir / "off" / "results.json");
    const auto cpu = read_json(dir / "cpu" / "results.json");
    const auto gpu = read_json(dir / "gpu" / "results.json");
    std::uint64_t tests_off = 0, tests_cpu = 0;
    for (size_t f = 0; f < cpu["frames"].size(); ++f) {
      if (!cpu["frames"][f]["stats"].contains("ccd")) continue;
      const auto& c = cpu["frames"][f]["stats"]["ccd"];
      const auto& g = gpu["frames"][f]["stats"]["ccd"];
      for (const char* key : {"elementary_tests", "triangle_pairs", "unshared_pairs", "culled_triangles", "object_pairs",
                              "voxelized_triangles"})
        EXPECT_EQ(c[key].get<std::uint64_t>(), g[key].get<std::uint64_t>()) << "frame " << f << " " << key;
      // The grid Stage II used is recorded (cells of 1/24 of the swept box's longest side, plus
      // the boundary cell); without Stage II there is none.
      ASSERT_TRUE(c.contains("grid") && c.contains("cell")) << c.dump();
      EXPECT_EQ(c["grid"], g["grid"]);
      EXPECT_EQ(std::max({c["grid"][0].get<int>(), c["grid"][1].get<int>(), c["grid"][2].get<int>()}), 25);
      EXPECT_GT(c["cell"].get<double>(), 0.0);
      EXPECT_FALSE(off["frames"][f]["stats"]["ccd"].contains("grid"));
      EXPECT_FALSE(off["frames"][f]["stats"]["ccd"].contains("voxelized_triangles"));
      EXPECT_GT(c["voxelized_triangles"].get<std::uint64_t>(), 0u);
      tests_cpu += c["elementary_tests"].get<std::uint64_t>();
      tests_off += off["frames"][f]["stats"]["ccd"]["elementary_tests"].get<std::uint64_t>();
    }
    EXPECT_LE(tests_cpu, tests_off);
    all_tests_cpu += tests_cpu;
    all_tests_off += tests_off;
  }
  EXPECT_LT(all_tests_cpu, all_tests_off) << "Stage II must cull some elementary tests in these scenes";
  EXPECT_GT(found, 0u) << "the scenes must have collisions for the comparison to mean much";
}

// --grid is the distance queries' grid and leaves CCD's own alone; --ccd-grid sets CCD's
// (finer CCD grids cost far more than they saved: docs/algorithms.md, "Continuous collision detection").
TEST(CcdCli, CcdGridIsSetByCcdGridAlone) {
  ScratchDir dir;
  const fs::path scene = write_scene(dir, 3, 4, 3);
  auto ccd_grids = [&](const std::string& options) {
    const auto out = dir / ("run" + std::to_string(std::hash<std::string>{}(options)));
    const auto r = vproxq(quote(scene) + " -o " + quote(out) + " --quiet --threads 2 --voronoi=cpu " + options);
    EXPECT_EQ(r.exit_code, 0) << options << ": " << r.output;
    std::vector<int> longest;
    const auto j = read_json(out / "results.json");
    for (const auto& f : j["frames"])
      if (f["stats"].contains("ccd") && f["stats"]["ccd"].contains("grid"))
        longest.push_back(std::max({f["stats"]["ccd"]["grid"][0].get<int>(), f["stats"]["ccd"]["grid"][1].get<int>(),
                                    f["stats"]["ccd"]["grid"][2].get<int>()}));
    return longest;
  };
  const std::vector<int> automatic = ccd_grids("");
  ASSERT_FALSE(automatic.empty());
  EXPECT_EQ(ccd_grids("--grid 24"), automatic);
  EXPECT_EQ(ccd_grids("--grid 24 --ccd-grid 24"), std::vector<int>(automatic.size(), 25));
  EXPECT_EQ(ccd_grids("--ccd-grid 24"), std::vector<int>(automatic.size(), 25));
  EXPECT_NE(automatic, std::vector<int>(automatic.size(), 25));
  // Like --grid, it has no effect without Stage II, and says so.
  const auto r = vproxq(quote(scene) + " --ccd-grid 24 -o " + quote(dir / "off"));
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("note: --ccd-grid has no effect with --voronoi=off"), std::string::npos) << r.output;
  for (const char* bad : {"--ccd-grid=0", "--ccd-grid=4097", "--ccd-grid=x"}) {
    const auto b = vproxq(quote(scene) + " " + bad + " --voronoi=cpu -o " + quote(dir / "bad"));
    EXPECT_EQ(b.exit_code, 2) << bad << ": " << b.output;
    EXPECT_NE(b.output.find("--ccd-grid"), std::string::npos) << b.output;
    EXPECT_FALSE(fs::exists(dir / "bad")) << bad;
  }
}

TEST(CcdCli, TopologyChangeIsSkippedWithReason) {
  ScratchDir dir;
  Frame f0 = test::make_random_frame(5, 3, 2.0, 1);
  Frame f1 = f0;
  auto topo = std::make_shared<Topology>(*f1.objects[1].topology);
  topo->faces.pop_back();  // a face disappears: the topology changes
  f1.objects[1].topology = topo;
  write_obj(f0, dir / "f_0.obj");
  write_obj(f1, dir / "f_1.obj");
  const auto scene = dir.write("scene.json", R"({"frames": {"pattern": "f_%d.obj", "first": 0, "count": 2}})");
  const auto r = vproxq(quote(scene) + " --queries=ccd,distance -o " + quote(dir / "out") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = read_json(dir / "out" / "results.json");
  const auto& skipped = j["frames"][0]["ccd"]["skipped"];
  ASSERT_EQ(skipped.size(), 1u);
  EXPECT_EQ(skipped[0]["object"].get<int>(), 1);
  EXPECT_NE(skipped[0]["reason"].get<std::string>().find("topology changes"), std::string::npos);
  EXPECT_TRUE(j["frames"][0].contains("distance"));
  const Hdf5Reader h5(dir / "out" / "results.h5");
  EXPECT_EQ(h5.rows("/frames/000000/ccd/skipped_objects"), 1u);
  const auto reasons = h5.strings_dataset("/frames/000000/ccd/skipped_reasons");
  ASSERT_EQ(reasons.size(), 1u);
  EXPECT_EQ(reasons[0], skipped[0]["reason"].get<std::string>());
}

// Objects named after each frame's file (a PLY frame holds one unnamed mesh) are matched by
// position; objects listed in another order in the next file are matched by name. Either way
// nothing is skipped and the collision is reported.
TEST(CcdCli, ObjectsAreMatchedAcrossFramesByPositionOrByName) {
  ScratchDir dir;
  auto ply = [](double z) {
    return "ply\nformat ascii 1.0\nelement vertex 6\nproperty double x\nproperty double y\n"
           "property double z\nelement face 2\nproperty list uchar int vertex_indices\nend_header\n"
           "0 0 0\n2 0 0\n0 2 0\n0.5 0.5 " + std::to_string(z) + "\n0.5 0.5 " + std::to_string(z + 1) +
           "\n0.5 1.5 " + std::to_string(z + 1) + "\n3 0 1 2\n3 3 4 5\n";
  };
  dir.write("a.ply", ply(0.5));
  dir.write("b.ply", ply(-0.5));
  auto r = vproxq(quote(dir.write("s1.json", R"({"frames": {"files": ["a.ply", "b.ply"]}})")) +
                  " --queries ccd --quiet -o " + quote(dir / "by_position"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  auto ccd = read_json(dir / "by_position" / "results.json")["frames"][0]["ccd"];
  EXPECT_TRUE(ccd["skipped"].empty()) << ccd.dump();
  EXPECT_EQ(ccd["pairs"].size(), 1u) << ccd.dump();

  const std::string tri = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";
  dir.write("o_0.obj", "o a\n" + tri + "f 1 2 3\no b\nv 0.2 0.2 0.5\nv 0.2 0.2 1.5\nv 0.2 1.2 1.5\nf 4 5 6\n");
  dir.write("o_1.obj", "o b\nv 0.2 0.2 -0.5\nv 0.2 0.2 0.5\nv 0.2 1.2 0.5\nf 1 2 3\no a\n" + tri + "f 4 5 6\n");
  r = vproxq(quote(dir.write("s2.json", R"({"frames": {"files": ["o_0.obj", "o_1.obj"]}})")) +
             " --queries ccd --quiet -o " + quote(dir / "by_name"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  ccd = read_json(dir / "by_name" / "results.json")["frames"][0]["ccd"];
  EXPECT_TRUE(ccd["skipped"].empty()) << ccd.dump();
  ASSERT_EQ(ccd["pairs"].size(), 1u) << ccd.dump();
  EXPECT_EQ(ccd["pairs"][0]["objects"], nlohmann::json::parse("[0, 1]"));
}


// "components": pieces are matched by their vertices' indices in the mesh, not by their names
// "blob#k" (which renumber when a piece in front breaks) nor by their faces (every tetrahedron
// has the same). Eight tetrahedra, none moving; piece 2 is two tetrahedra sharing a vertex, and
// in frame 1 that vertex is duplicated, so the piece breaks in two. Matched by name, the pieces
// behind it were paired with their neighbours, and piece 4 swept through piece 1 (a phantom
// collision).
TEST(CcdCli, PiecesOfBrokenMeshesAreMatchedByTheirVertices) {
  ScratchDir dir;
  struct Tet {
    std::vector<Vec3> v;
    std::vector<Face> f;
  };
  auto tet_at = [](double x, double y) {
    return Tet{{Vec3(x, y, 0), Vec3(x + 0.8, y, 0), Vec3(x, y + 0.8, 0), Vec3(x, y, 0.8)},
               {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}};
  };
  // Piece 1 lies on the way from piece 4 to piece 3: pairing piece 4 with the piece that
  // takes its number after the break (piece 3) sweeps it through piece 1.
  const double where[8][2] = {{-6, 6}, {2, 0}, {2, 6}, {0, 0}, {4, 0}, {7, 0}, {10, 0}, {13, 0}};
  auto slot = [&](int k) { return tet_at(where[k][0], where[k][1]); };
  // Piece 2 of frame 0: slot 2's tetrahedron and a second one hanging from its vertex 3.
  const Tet a = slot(2);
  Tet b{{a.v[3], a.v[3] + Vec3(0.5, 0, 0.3), a.v[3] + Vec3(0, 0.5, 0.3), a.v[3] + Vec3(0, 0, 0.6)},
        {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}}};
  // One OBJ mesh from pieces; `split` makes piece 2's second tetrahedron use its own copy of
  // the shared vertex, written right after the first tetrahedron's vertices (`in_front`: the
  // indices of every later vertex shift by one) or after all others (they keep theirs).
  auto write = [&](const fs::path& file, bool split, bool in_front) {
    std::vector<Vec3> v;
    std::vector<Face> f;
    auto add = [&](const Tet& t, const std::vector<Index>& ids) {
      for (const Face& face : t.f) f.push_back({ids[face[0]], ids[face[1]], ids[face[2]]});
    };
    Index extra = kNoIndex;
    std::vector<std::vector<Index>> ids(9);
    for (int k = 0; k < 8; ++k) {
      const Tet t = k == 2 ? a : slot(k);
      for (const Vec3& p : t.v) {
        ids[k].push_back(static_cast<Index>(v.size()));
        v.push_back(p);
      }
      if (k == 2) {  // b's own vertices 1..3, and the copy of the shared one when split
        if (split && in_front) {
          extra = static_cast<Index>(v.size());
          v.push_back(b.v[0]);
        }
        ids[8] = {ids[2][3]};
        for (int c = 1; c < 4; ++c) {
          ids[8].push_back(static_cast<Index>(v.size()));
          v.push_back(b.v[static_cast<size_t>(c)]);
        }
      }
    }
    if (split && !in_front) {
      extra = static_cast<Index>(v.size());
      v.push_back(b.v[0]);
    }
    if (split) ids[8][0] = extra;
    for (int k = 0; k < 8; ++k) {
      add(k == 2 ? a : slot(k), ids[static_cast<size_t>(k)]);
      if (k == 2) add(b, ids[8]);
    }
    std::ofstream out(file);
    out.precision(17);
    out << "o blob\n";
    for (const Vec3& p : v) out << "v " << p.x() << " " << p.y() << " " << p.z() << "\n";
    for (const Face& face : f) out << "f " << face[0] + 1 << " " << face[1] + 1 << " " << face[2] + 1 << "\n";
  };
  write(dir / "whole.obj", false, false);
  write(dir / "end.obj", true, false);
  write(dir / "front.obj", true, true);
  for (const bool in_front : {false, true}) {
    SCOPED_TRACE(in_front ? "copy in front of later pieces" : "copy after all vertices");
    const std::string next = in_front ? "front.obj" : "end.obj";
    const auto scene = dir.write("s.json", R"({"frames": {"files": ["whole.obj", ")" + next +
                                               R"("]}, "objects": "components"})");
    const fs::path out = dir / (in_front ? "out_front" : "out_end");
    const auto r = vproxq(quote(scene) + " --queries ccd --quiet -o " + quote(out));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const auto ccd = read_json(out / "results.json")["frames"][0]["ccd"];
    // Nothing moves: no collision, whatever is matched.
    EXPECT_TRUE(ccd["pairs"].empty()) << ccd.dump();
    // The broken piece has no counterpart; with the copy in front, neither has any piece
    // behind it (its vertices' indices changed), otherwise those are matched.
    std::vector<int> skipped;
    for (const auto& s : ccd["skipped"]) skipped.push_back(s["object"].get<int>());
    const std::vector<int> expected = in_front ? std::vector<int>{2, 3, 4, 5, 6, 7} : std::vector<int>{2};
    EXPECT_EQ(skipped, expected) << ccd.dump();
    ASSERT_FALSE(ccd["skipped"].empty());
    EXPECT_NE(ccd["skipped"][0]["reason"].get<std::string>().find("no piece of 'blob' in frame 1 holds the same vertices"),
              std::string::npos)
        << ccd.dump();
  }
}


// Pieces renumbered without breaking (the file lists the mesh's faces in another order) are
// still matched by their vertices: the same collisions, with frame 0's object ids, as when the
// faces keep their order.
TEST(CcdCli, RenumberedPiecesKeepTheirCollisions) {
  ScratchDir dir;
  auto tet = [](double x, double y, double z) {
    std::string v;
    for (const auto& d : {std::array<double, 3>{0, 0, 0}, {0.8, 0, 0}, {0, 0.8, 0}, {0, 0, 0.8}})
      v += "v " + std::to_string(x + d[0]) + " " + std::to_string(y + d[1]) + " " + std::to_string(z + d[2]) + "\n";
    return v;
  };
  auto faces = [](int base) {
    std::string f;
    for (const auto& t : {std::array<int, 3>{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}})
      f += "f " + std::to_string(base + t[0] + 1) + " " + std::to_string(base + t[1] + 1) + " " +
           std::to_string(base + t[2] + 1) + "\n";
    return f;
  };
  // Pieces 0, 1, 2; piece 0 moves through piece 1 in the step.
  dir.write("f0.obj", "o blob\n" + tet(0, 0, 0) + tet(2, 0, 0) + tet(5, 3, 0) + faces(0) + faces(4) + faces(8));
  const std::string moved = "o blob\n" + tet(4, 0, 0) + tet(2, 0, 0) + tet(5, 3, 0);
  dir.write("same.obj", moved + faces(0) + faces(4) + faces(8));
  dir.write("reordered.obj", moved + faces(8) + faces(4) + faces(0));  // pieces 2, 1, 0 -> #0, #1, #2
  nlohmann::json got[2];
  for (int k = 0; k < 2; ++k) {
    const std::string next = k ? "reordered.obj" : "same.obj";
    const auto scene = dir.write("s.json", R"({"frames": {"files": ["f0.obj", ")" + next +
                                               R"("]}, "objects": "components"})");
    const auto r = vproxq(quote(scene) + " --queries ccd --quiet -o " + quote(dir / ("out" + std::to_string(k))));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    got[k] = read_json(dir / ("out" + std::to_string(k)) / "results.json")["frames"][0]["ccd"];
    EXPECT_TRUE(got[k]["skipped"].empty()) << got[k].dump();
    ASSERT_EQ(got[k]["pairs"].size(), 1u) << got[k].dump();
    EXPECT_EQ(got[k]["pairs"][0]["objects"], nlohmann::json::parse("[0, 1]")) << got[k].dump();
  }
  EXPECT_EQ(got[0]["pairs"], got[1]["pairs"]);
  EXPECT_EQ(got[0]["vf"], got[1]["vf"]);
  EXPECT_EQ(got[0]["ee"], got[1]["ee"]);
}

// Meshes the file does not name (a PLY or OFF file, an OBJ without groups, faces before the
// first OBJ group) are named after the file, which changes from frame to frame: their pieces
// are matched by the mesh's position in the file instead, so the usual frames/x_%04d.ply
// layout keeps its collisions. The same step through two files of one name is the reference.
TEST(CcdCli, PiecesOfMeshesNamedAfterTheirFileAreMatched) {
  ScratchDir dir;
  auto tet = [](double x) {
    std::vector<Vec3> v;
    for (const auto& d : {Vec3(0, 0, 0), Vec3(0.8, 0, 0), Vec3(0, 0.8, 0), Vec3(0, 0, 0.8)}) v.push_back(Vec3(x, 0, 0) + d);
    return v;
  };
  const std::vector<std::array<int, 3>> tet_faces = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
  // Piece 0 moves from x = 0 to x = 4 through piece 1 at x = 2; piece 2 stays apart.
  auto points = [&](double x0) {
    std::vector<Vec3> v;
    for (double x : {x0, 2.0, 6.0})
      for (const Vec3& p : tet(x)) v.push_back(p);
    return v;
  };
  auto obj = [&](const std::vector<Vec3>& v, const std::string& header, int grouped_from) {
    std::ostringstream out;
    out.precision(17);
    out << header;
    for (const Vec3& p : v) out << "v " << p.x() << " " << p.y() << " " << p.z() << "\n";
    for (int t = 0; t < 3; ++t) {
      if (t == grouped_from) out << "o named\n";
      for (const auto& f : tet_faces) out << "f " << 4 * t + f[0] + 1 << " " << 4 * t + f[1] + 1 << " " << 4 * t + f[2] + 1 << "\n";
    }
    return out.str();
  };
  auto ply = [&](const std::vector<Vec3>& v) {
    std::ostringstream out;
    out.precision(17);
    out << "ply\nformat ascii 1.0\nelement vertex " << v.size()
        << "\nproperty double x\nproperty double y\nproperty double z\nelement face 12\n"
           "property list uchar int vertex_indices\nend_header\n";
    for (const Vec3& p : v) out << p.x() << " " << p.y() << " " << p.z() << "\n";
    for (int t = 0; t < 3; ++t)
      for (const auto& f : tet_faces) out << "3 " << 4 * t + f[0] << " " << 4 * t + f[1] << " " << 4 * t + f[2] << "\n";
    return out.str();
  };
  // (files of frame 0 and 1, same-name files for the reference); grouped_from 3: no group.
  struct Layout {
    const char* what;
    std::string a, b, ref_a, ref_b, text_a, text_b;
  };
  const std::vector<Layout> layouts = {
      {"ungrouped OBJ", "x_0000.obj", "x_0001.obj", "a/x.obj", "b/x.obj", obj(points(0), "", 3), obj(points(4), "", 3)},
      {"faces before the first OBJ group", "y_0000.obj", "y_0001.obj", "c/y.obj", "d/y.obj", obj(points(0), "", 2),
       obj(points(4), "", 2)},
      {"PLY", "z_0000.ply", "z_0001.ply", "e/z.ply", "f/z.ply", ply(points(0)), ply(points(4))},
  };
  for (const Layout& l : layouts) {
    SCOPED_TRACE(l.what);
    for (const auto& [file, text] : {std::pair{l.a, l.text_a}, {l.b, l.text_b}, {l.ref_a, l.text_a}, {l.ref_b, l.text_b}}) {
      fs::create_directories((dir / file).parent_path());
      dir.write(file, text);
    }
    nlohmann::json got[2];
    for (int k = 0; k < 2; ++k) {
      const std::string files = k ? "\"" + l.ref_a + "\", \"" + l.ref_b + "\"" : "\"" + l.a + "\", \"" + l.b + "\"";
      const auto scene = dir.write("s.json", R"({"frames": {"files": [)" + files + R"(]}, "objects": "components"})");
      const fs::path out = dir / ("out_" + std::string(l.a) + std::to_string(k));
      const auto r = vproxq(quote(scene) + " --queries ccd --quiet -o " + quote(out));
      ASSERT_EQ(r.exit_code, 0) << r.output;
      got[k] = read_json(out / "results.json")["frames"][0]["ccd"];
      EXPECT_TRUE(got[k]["skipped"].empty()) << got[k].dump();
    }
    ASSERT_EQ(got[0]["pairs"].size(), 1u) << got[0].dump();
    EXPECT_EQ(got[0]["pairs"][0]["objects"], nlohmann::json::parse("[0, 1]")) << got[0].dump();
    EXPECT_EQ(got[0]["pairs"], got[1]["pairs"]);
    EXPECT_EQ(got[0]["vf"], got[1]["vf"]);
    EXPECT_EQ(got[0]["ee"], got[1]["ee"]);
  }
}

// Meshes the files do not name must not be taken for one another: two static PLY files (both
// hold their file's only unnamed mesh) are told apart by the file, and of several unnamed
// OBJ groups in one file none is matched (by position, a group that vanished and its
// neighbour would read as one moving mesh). Nothing here moves: any pair is a phantom.
TEST(CcdCli, UnnamedMeshesAreNotTakenForOneAnother) {
  ScratchDir dir;
  auto tet = [](double x, double y) {
    std::string v;
    for (const auto& d : {std::array<double, 3>{0, 0, 0}, {0.8, 0, 0}, {0, 0.8, 0}, {0, 0, 0.8}})
      v += "v " + std::to_string(x + d[0]) + " " + std::to_string(y + d[1]) + " " + std::to_string(d[2]) + "\n";
    return v;
  };
  const std::string faces = "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
  auto ply = [&](double x) {
    std::string out = "ply\nformat ascii 1.0\nelement vertex 4\nproperty double x\nproperty double y\n"
                      "property double z\nelement face 4\nproperty list uchar int vertex_indices\nend_header\n";
    std::string v = tet(x, 5);
    for (std::size_t at; (at = v.find("v ")) != std::string::npos;) v.erase(at, 2);
    return out + v + "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n";
  };
  dir.write("s1.ply", ply(0));
  dir.write("s2.ply", ply(3));
  // The named mesh loses its first piece: the second is skipped (its vertices' indices
  // changed; the first piece's indices now hold it, which reads as that piece moving), and the
  // statics behind it change places in the object list: each must find its own file's.
  dir.write("d0.obj", "o m\n" + tet(0, 0) + tet(3, 0) + faces + "f 5 7 6\nf 5 6 8\nf 5 8 7\nf 6 7 8\n");
  dir.write("d1.obj", "o m\n" + tet(3, 0) + faces);
  auto group = [&](const std::string& g, double x, int base) {
    std::string f;
    for (const auto& t : {std::array<int, 3>{1, 3, 2}, {1, 2, 4}, {1, 4, 3}, {2, 3, 4}})
      f += "f " + std::to_string(base + t[0]) + " " + std::to_string(base + t[1]) + " " + std::to_string(base + t[2]) + "\n";
    return std::pair{tet(x, 0), g + "\n" + f};
  };
  // Frame 0: bare groups X (x = 0), Y (x = 3), then Z (x = 6); frame 1 drops X.
  const auto [xv, xf] = group("g", 0, 0);
  const auto [yv, yf] = group("g", 3, 4);
  const auto [zv, zf] = group("g Z", 6, 8);
  dir.write("u0.obj", xv + yv + zv + xf + yf + zf);
  const auto [yv1, yf1] = group("g", 3, 0);
  const auto [zv1, zf1] = group("g Z", 6, 4);
  dir.write("u1.obj", yv1 + zv1 + yf1 + zf1);
  for (const auto& [scene_text, expected_skipped] : std::vector<std::pair<std::string, std::vector<int>>>{
           {R"({"frames": {"files": ["d0.obj", "d1.obj"]}, "objects": "components", "static": ["s1.ply", "s2.ply"]})", {1}},
           {R"({"frames": {"files": ["u0.obj", "u1.obj"]}, "objects": "components"})", {0, 1}}}) {
    SCOPED_TRACE(scene_text);
    const auto scene = dir.write("s.json", scene_text);
    const fs::path out = dir / ("out" + std::to_string(scene_text.size()));
    const auto r = vproxq(quote(scene) + " --queries ccd --quiet -o " + quote(out));
    ASSERT_EQ(r.exit_code, 0) << r.output;
    const auto ccd = read_json(out / "results.json")["frames"][0]["ccd"];
    EXPECT_TRUE(ccd["pairs"].empty()) << ccd.dump();
    std::vector<int> skipped;
    for (const auto& sk : ccd["skipped"]) skipped.push_back(sk["object"].get<int>());
    EXPECT_EQ(skipped, expected_skipped) << ccd.dump();
  }
}

}  // namespace
}  // namespace vproxq
