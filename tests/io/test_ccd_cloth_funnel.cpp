// The cloth-funnel step 227 -> 228 (tests/data/frames/cloth-funnel, one object of 9,450
// vertices and 18,484 triangles) through the whole CCD pipeline, checked against the data's
// Mathematica ground truth (mma_bool): every pair marked true must be reported. Pairs marked
// false that are reported anyway (conservative false positives) are counted and printed.
// Id mapping (tests/data/NOTICE.md): one list of all vertices, then all unique edges sorted by
// (larger, smaller) vertex, then all faces; vf pairs are (v, nV+nE+f), ee pairs (nV+a, nV+b).
#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/mesh/adjacency.hpp"
#include "core/query/ccd.hpp"
#include "core/voronoi/ccd_stage2.hpp"
#include "io/scene_source.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <set>
#include <tuple>

namespace vproxq {
namespace {

namespace fs = std::filesystem;
const fs::path kDir = fs::path(VPROXQ_TEST_DATA_DIR) / "frames" / "cloth-funnel";

nlohmann::json read_json(const fs::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

struct Counts {
  long truth_true = 0, truth_true_reported = 0, truth_false = 0, truth_false_reported = 0;
};

void check_against_ground_truth(const Frame& from, const CcdStepResult& r, Counts& vf, Counts& ee) {
  const Topology& topo = *from.objects[0].topology;
  const Adjacency& adj = adjacency(topo);
  const long nv = topo.num_vertices;
  const long ne = static_cast<long>(adj.edges().size());
  std::set<std::pair<Index, Index>> vf_hits;
  for (const auto& h : r.vf) vf_hits.insert({h.vertex, h.face});
  std::set<std::pair<std::array<Index, 2>, std::array<Index, 2>>> ee_hits;
  for (const auto& h : r.ee) {
    ee_hits.insert({h.edge_a, h.edge_b});
    ee_hits.insert({h.edge_b, h.edge_a});
  }
  const auto boxes_vf = read_json(kDir / "boxes/227vf.json");
  const auto truth_vf = read_json(kDir / "mma_bool/227vf_mma_bool.json");
  ASSERT_EQ(boxes_vf.size(), truth_vf.size());
  for (size_t k = 0; k < boxes_vf.size(); ++k) {
    const long v = boxes_vf[k][0].get<long>();
    const long f = boxes_vf[k][1].get<long>() - nv - ne;
    ASSERT_TRUE(v >= 0 && v < nv && f >= 0 && f < topo.num_triangles()) << "vf pair " << k;
    const bool reported = vf_hits.count({static_cast<Index>(v), static_cast<Index>(f)}) > 0;
    if (truth_vf[k].get<bool>()) {
      ++vf.truth_true;
      vf.truth_true_reported += reported;
      EXPECT_TRUE(reported) << "missed vf pair " << k << ": vertex " << v << " face " << f;
    } else {
      ++vf.truth_false;
      vf.truth_false_reported += reported;
    }
  }
  const auto boxes_ee = read_json(kDir / "boxes/227ee.json");
  const auto truth_ee = read_json(kDir / "mma_bool/227ee_mma_bool.json");
  ASSERT_EQ(boxes_ee.size(), truth_ee.size());
  for (size_t k = 0; k < boxes_ee.size(); ++k) {
    const long a = boxes_ee[k][0].get<long>() - nv, b = boxes_ee[k][1].get<long>() - nv;
    ASSERT_TRUE(a >= 0 && a < ne && b >= 0 && b < ne) << "ee pair " << k;
    const auto& ea = adj.edges()[static_cast<size_t>(a)];
    const auto& eb = adj.edges()[static_cast<size_t>(b)];
    const bool reported = ee_hits.count({ea, eb}) > 0;
    if (truth_ee[k].get<bool>()) {
      ++ee.truth_true;
      ee.truth_true_reported += reported;
      EXPECT_TRUE(reported) << "missed ee pair " << k << ": edges " << a << ", " << b;
    } else {
      ++ee.truth_false;
      ee.truth_false_reported += reported;
    }
  }
}

TEST(CcdClothFunnel, EveryTruePairIsReported) {
  const SceneSource scene = SceneSource::open(kDir / "scene.json");
  ASSERT_EQ(scene.frame_count(), 2u);
  const Frame from = scene.load_frame(0);
  const Frame to = scene.load_frame(1);
  ASSERT_EQ(from.objects.size(), 1u);
  ASSERT_EQ(from.objects[0].num_vertices(), 9450);
  ASSERT_EQ(from.objects[0].num_triangles(), 18484);
  const CcdSweep sweep = CcdSweep::compute(from, to, 2);
  const CcdVoxelCulling voxels(from, to, sweep, 0, 2);
  for (const bool stage2 : {false, true}) {
    SCOPED_TRACE(stage2 ? "voxel culling" : "AABB culling");
    const CcdStepResult r = continuous_collisions(from, to, sweep, CcdOptions{2, stage2 ? &voxels : nullptr});
    EXPECT_TRUE(r.skipped.empty());
    Counts vf, ee;
    check_against_ground_truth(from, r, vf, ee);
    EXPECT_EQ(vf.truth_true, 27);
    EXPECT_EQ(ee.truth_true, 107);
    std::printf("[          ] %s: vf true %ld, reported %ld; vf false %ld, reported anyway %ld | "
                "ee true %ld, reported %ld; ee false %ld, reported anyway %ld | colliding pairs "
                "found: vf %zu, ee %zu; elementary tests %llu (vf %llu, ee %llu), limit hits %llu\n",
                stage2 ? "voxels" : "aabb", vf.truth_true, vf.truth_true_reported, vf.truth_false,
                vf.truth_false_reported, ee.truth_true, ee.truth_true_reported, ee.truth_false,
                ee.truth_false_reported, r.vf.size(), r.ee.size(),
                static_cast<unsigned long long>(r.counters.elementary_tests()),
                static_cast<unsigned long long>(r.counters.vf_tests),
                static_cast<unsigned long long>(r.counters.ee_tests),
                static_cast<unsigned long long>(r.counters.limit_hits));
  }
}

}  // namespace
}  // namespace vproxq
