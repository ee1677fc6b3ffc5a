// Stage II for CCD (core/voronoi/ccd_stage2.hpp): the CPU backend's row solver against the
// voxel-by-voxel reference on random records (keys and co-occupancy flags), conservativeness
// of the space-time voxelization (every point a moving triangle passes through, widened by
// the margin, lies in a marked voxel of its time slot), and the pipeline with time slots:
// equal to brute force, and culling what prisms alone cannot (a fast-moving object's front
// and back).
#include <gtest/gtest.h>

#include "core/query/ccd.hpp"
#include "core/voronoi/ccd_stage2.hpp"
#include "support/ccd_voxels.hpp"
#include "support/expect_same.hpp"
#include "support/random_scene.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <map>
#include <set>
#include <utility>

namespace vproxq {
namespace {

using test::moved;

TEST(CcdStage2, RowSolverEqualsVoxelByVoxelReference) {
  std::size_t marked = 0, flagged = 0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const CcdVoxelInput in = test::random_ccd_voxel_input(seed, {7 + static_cast<int>(seed), 9, 5 + static_cast<int>(seed % 3)}, 4, 300);
    for (int threads : {1, 3}) {
      const CcdVoxelOutput out = make_cpu_ccd_voxel_backend(threads)->voxelize(in);
      test::expect_ccd_output_matches_reference(in, out);
      if (threads == 1) {
        for (std::uint32_t c : out.counts) marked += c;
        for (std::uint32_t f : out.foreign) flagged += f;
      }
    }
  }
  // The records must mark some voxels and leave others, and co-occupancy must occur.
  EXPECT_GT(marked, 1000u);
  EXPECT_GT(flagged, 100u);
}

/// The point of triangle t (object o) at time tau with barycentrics (1 - u - v, u, v), moving
/// linearly between the frames.
Vec3 point_at(const Frame& from, const Frame& to, Index o, Index t, double tau, double u, double v) {
  const Face& f = from.objects[static_cast<size_t>(o)].topology->faces[static_cast<size_t>(t)];
  auto corner = [&](int c) {
    const Vec3& a = from.objects[static_cast<size_t>(o)].positions[static_cast<size_t>(f[static_cast<size_t>(c)])];
    const Vec3& b = to.objects[static_cast<size_t>(o)].positions[static_cast<size_t>(f[static_cast<size_t>(c)])];
    return Vec3(a + tau * (b - a));
  };
  return (1 - u - v) * corner(0) + u * corner(1) + v * corner(2);
}

TEST(CcdStage2, EveryPointSweptWithinTheMarginIsInAMarkedVoxelOfItsSlot) {
  Frame from = test::make_random_frame(21, 4, 2.0, 1);
  test::Rng rng(22);
  from.objects.push_back(test::make_soup(rng, Vec3(1, 1, 1), 0.8, 0.4, 30, "soup"));
  const Frame to = moved(from, 23, 0.8, 0.3);
  CcdSweep sweep = CcdSweep::compute(from, to, 2);
  // A margin far larger than the real one, so that the widening is exercised; the boxes grow
  // with it (they must hold every widened hull).
  const double extra = 0.03;
  sweep.margin += extra;
  for (size_t i = 0; i < sweep.triangles.size(); ++i) {
    AABB box;
    for (AABB& b : sweep.triangles[i]) {
      b.lo.array() -= extra;
      b.hi.array() += extra;
      box.extend(b);
    }
    sweep.objects[i] = box;
  }
  const auto backend = make_cpu_ccd_voxel_backend(2);
  // Also with only some triangles voxelized (as CCD does, for the triangles of its candidate
  // pairs): every other triangle, and none of object 1; the grid then covers only those, so
  // their points must still land in marked voxels. The others have no keys and rule nothing out.
  CcdTriangleMask some(from.objects.size());
  for (size_t o = 0; o < from.objects.size(); ++o)
    for (Index t = 0; t < from.objects[o].num_triangles(); ++t) some[o].push_back(o != 1 && t % 2 == 0);
  std::size_t checked = 0, left_out = 0;
  const std::array<const CcdTriangleMask*, 2> masks{nullptr, &some};
  for (const CcdTriangleMask* only : masks) for (int slots : {1, 2, 4, 8}) {
    for (int grid : {0, 9, 40}) {
      SCOPED_TRACE("slots " + std::to_string(slots) + " grid " + std::to_string(grid) + (only ? " (some)" : ""));
      const CcdVoxelCulling vox(from, to, sweep, CcdVoxelOptions{grid, slots, 2}, *backend, only);
      ASSERT_EQ(vox.slots(), slots);
      const VoronoiGrid& g = vox.grid();
      std::uint64_t voxelized = 0;
      for (Index o = 0; o < static_cast<Index>(from.objects.size()); ++o) {
        for (Index t = 0; t < from.objects[static_cast<size_t>(o)].num_triangles(); ++t) {
          if (only && !some[static_cast<size_t>(o)][static_cast<size_t>(t)]) {
            EXPECT_TRUE(vox.keys(o, t).empty());
            EXPECT_TRUE(vox.keeps(o, t));
            EXPECT_TRUE(vox.share_voxel(o, t, 0, 0));
            EXPECT_TRUE(vox.share_voxel(0, 0, o, t));
            ++left_out;
            continue;
          }
          ++voxelized;
          if (t % 3 != 0) continue;
          const std::vector<std::uint32_t> keys = vox.keys(o, t);
          ASSERT_TRUE(std::is_sorted(keys.begin(), keys.end()));
          for (int sample = 0; sample < 12; ++sample) {
            // Slot boundaries, the ends and random times; corners, edges and inside points;
            // offsets at the margin's corners or random within it.
            const double tau = sample < 3 ? sample / 2.0 : (sample < 5 ? (sample - 2) / static_cast<double>(slots) - 1e-17 : rng.uniform(0, 1));
            double u = rng.uniform(0, 1), v = rng.uniform(0, 1);
            if (u + v > 1) u = 1 - u, v = 1 - v;
            if (sample % 4 == 0) u = 0, v = sample % 8 == 0 ? 0 : 1;
            Vec3 off = rng.vec3(-1, 1);
            if (sample % 3 == 0) off = off.array().sign();
            const Vec3 q = point_at(from, to, o, t, std::clamp(tau, 0.0, 1.0), u, v) + sweep.margin * off;
            const Vec3 rel = (q - g.origin) / g.cell;
            std::int64_t id = 0, stride = 1;
            for (int k = 0; k < 3; ++k) {
              const std::int64_t x = std::clamp<std::int64_t>(static_cast<std::int64_t>(std::floor(rel[k])), 0, g.dims[k] - 1);
              id += x * stride;
              stride *= g.dims[k];
            }
            const double tc = std::clamp(tau, 0.0, 1.0);
            const std::int64_t slot = std::min<std::int64_t>(slots - 1, static_cast<std::int64_t>(std::floor(tc * slots)));
            const std::uint32_t key = static_cast<std::uint32_t>(slot * g.voxel_count() + id);
            ASSERT_TRUE(std::binary_search(keys.begin(), keys.end(), key))
                << "object " << o << " triangle " << t << " tau " << tau << " point " << q.transpose();
            ++checked;
          }
        }
      }
      EXPECT_EQ(vox.voxelized_triangles(), voxelized);
    }
  }
  EXPECT_GT(checked, 5000u);
  EXPECT_GT(left_out, 500u);
}

/// A blob moving one diameter in the step into a smaller one: the swept prisms of its front
/// and back overlap (the front sweeps through where the back was), but never at the same time.
std::pair<Frame, Frame> fast_blob_step() {
  test::Rng rng(3);
  Frame from;
  from.objects.push_back(test::make_blob(rng, Vec3(0, 0, 0), 1.0, 2, 0.05, "fast"));
  from.objects.push_back(test::make_blob(rng, Vec3(2.2, 0.3, 0), 0.5, 2, 0.05, "target"));
  Frame to = from;
  to.index = 1;
  for (Vec3& p : to.objects[0].positions) p += Vec3(2, 0.1, 0);  // runs into the target
  return {from, to};
}

TEST(CcdStage2, TimeSlotsCullAFastObjectsFrontAgainstItsBack) {
  const auto [from, to] = fast_blob_step();
  const CcdStepResult ref = continuous_collisions_brute_force(from, to);
  EXPECT_GT(ref.vf.size() + ref.ee.size(), 0u);
  const CcdSweep sweep = CcdSweep::compute(from, to, 2);
  const auto backend = make_cpu_ccd_voxel_backend(2);
  std::map<int, std::uint64_t> pairs;
  for (int slots : {1, 4, 16}) {
    SCOPED_TRACE("slots " + std::to_string(slots));
    const CcdVoxelCulling vox(from, to, sweep, CcdVoxelOptions{0, slots, 2}, *backend);
    const CcdStepResult r = continuous_collisions(from, to, sweep, CcdOptions{2, &vox});
    EXPECT_EQ(r.vf.size(), ref.vf.size());
    EXPECT_EQ(r.ee.size(), ref.ee.size());
    for (size_t k = 0; k < std::min(r.vf.size(), ref.vf.size()); ++k) EXPECT_EQ(r.vf[k].toi, ref.vf[k].toi);
    for (size_t k = 0; k < std::min(r.ee.size(), ref.ee.size()); ++k) EXPECT_EQ(r.ee[k].toi, ref.ee[k].toi);
    // The fast blob's triangle pairs that share a (slot, voxel) key. CCD tests a pair's keys
    // after its separating-axis test, which on this step already shows apart almost every pair
    // that slots separate, so the keys are counted here directly.
    std::uint64_t sharing = 0;
    const Index n = from.objects[0].num_triangles();
    for (Index f = 0; f < n; ++f)
      for (Index g = f + 1; g < n; ++g) sharing += vox.share_voxel(0, f, 0, g);
    pairs[slots] = sharing;
  }
  std::printf("[          ] fast blob's triangle pairs sharing a key with 1 / 4 / 16 slots: %llu / %llu / %llu\n",
              static_cast<unsigned long long>(pairs[1]), static_cast<unsigned long long>(pairs[4]),
              static_cast<unsigned long long>(pairs[16]));
  // Measured: 4,816 / 1,326 / 970 of 8,128 pairs (one slot is the prism test).
  EXPECT_LT(pairs[4], pairs[1]);
  EXPECT_LT(pairs[16], pairs[4]);
}

TEST(CcdStage2, RandomStepsEqualBruteForceWithEverySlotCount) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Frame from = test::make_random_frame(seed + 40, 5, 3.0, 1);
    const Frame to = moved(from, seed * 7, 0.8, seed % 2 ? 0.25 : 0.05);
    const CcdStepResult ref = continuous_collisions_brute_force(from, to);
    const CcdSweep sweep = CcdSweep::compute(from, to, 2);
    const auto backend = make_cpu_ccd_voxel_backend(2);
    for (int slots : {1, 2, 8}) {
      for (int grid : {0, 5, 50}) {
        SCOPED_TRACE("slots " + std::to_string(slots) + " grid " + std::to_string(grid));
        const CcdVoxelCulling vox(from, to, sweep, CcdVoxelOptions{grid, slots, 2}, *backend);
        const CcdStepResult r = continuous_collisions(from, to, sweep, CcdOptions{2, &vox});
        ASSERT_EQ(r.vf.size(), ref.vf.size());
        ASSERT_EQ(r.ee.size(), ref.ee.size());
        for (size_t k = 0; k < r.vf.size(); ++k) {
          EXPECT_EQ(r.vf[k].vertex, ref.vf[k].vertex);
          EXPECT_EQ(r.vf[k].face, ref.vf[k].face);
          EXPECT_EQ(r.vf[k].toi, ref.vf[k].toi);
        }
        for (size_t k = 0; k < r.ee.size(); ++k) {
          EXPECT_EQ(r.ee[k].edge_a, ref.ee[k].edge_a);
          EXPECT_EQ(r.ee[k].edge_b, ref.ee[k].edge_b);
          EXPECT_EQ(r.ee[k].toi, ref.ee[k].toi);
        }
      }
    }
  }
}

// Stage II built inside continuous_collisions(), after Stage I, over the triangles of the pairs
// Stage I leaves: equal to the brute force with every slot count and grid, on random steps and
// on the fast blob, with fewer triangles voxelized than there are.
TEST(CcdStage2, BuiltOverTheCandidatePairsEqualsBruteForce) {
  const auto backend = make_cpu_ccd_voxel_backend(2);
  std::uint64_t unshared = 0, culled = 0, voxelized = 0, triangles = 0;
  auto check = [&](const Frame& from, const Frame& to) {
    const CcdStepResult ref = continuous_collisions_brute_force(from, to);
    const CcdSweep sweep = CcdSweep::compute(from, to, 2);
    const CcdStepResult off = continuous_collisions(from, to, sweep, CcdOptions{2});
    std::uint64_t n = 0;
    for (const Object& o : from.objects) n += static_cast<std::uint64_t>(o.num_triangles());
    for (int slots : {1, 2, 8, 16}) {
      for (int grid : {0, 5, 50}) {
        SCOPED_TRACE("slots " + std::to_string(slots) + " grid " + std::to_string(grid));
        CcdOptions opts{2};
        opts.voxel_backend = backend.get();
        opts.voxel_slots = slots;
        opts.voxel_grid = grid;
        const CcdStepResult r = continuous_collisions(from, to, sweep, opts);
        test::expect_same_ccd(r, ref);
        EXPECT_TRUE(r.stage2);
        ASSERT_TRUE(r.voxel_grid.has_value());
        // The same Stage I as without Stage II; what Stage II drops is not tested.
        EXPECT_EQ(r.counters.triangle_pairs, off.counters.triangle_pairs);
        EXPECT_EQ(r.counters.separated_pairs, off.counters.separated_pairs);
        EXPECT_LE(r.counters.elementary_tests(), off.counters.elementary_tests());
        EXPECT_GT(r.counters.voxelized_triangles, 0u);
        EXPECT_LE(r.counters.voxelized_triangles, n);
        unshared += r.counters.unshared_pairs;
        culled += r.counters.culled_triangles;
        voxelized += r.counters.voxelized_triangles;
        triangles += n;
      }
    }
  };
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Frame from = test::make_random_frame(seed + 40, 5, 3.0, 1);
    check(from, moved(from, seed * 7, 0.8, seed % 2 ? 0.25 : 0.05));
  }
  {
    SCOPED_TRACE("fast blob");
    const auto [from, to] = fast_blob_step();
    check(from, to);
  }
  std::printf("[          ] Stage II over the candidate pairs: %llu of %llu triangles voxelized, "
              "%llu pairs and %llu triangles culled\n",
              static_cast<unsigned long long>(voxelized), static_cast<unsigned long long>(triangles),
              static_cast<unsigned long long>(unshared), static_cast<unsigned long long>(culled));
  EXPECT_LT(voxelized, triangles);
  EXPECT_GT(unshared, 0u);  // it culls something, or equality with the brute force proves little
}

// Stage II looks at pairs of triangles of different objects only: pairs within one object go
// from Stage I to Stage III (on the report scenes it ruled out almost none of them, while
// most of the triangles it voxelized were there for them alone). A lone object folding onto
// itself then voxelizes nothing, and runs the tests it runs without Stage II; two objects
// voxelize only triangles of pairs between them.
TEST(CcdStage2, PairsWithinOneObjectAreLeftToStageOne) {
  const auto backend = make_cpu_ccd_voxel_backend(2);
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    Frame from = test::make_random_frame(seed + 70, 1, 1.0, 2);
    from.index = 0;
    const Frame to = moved(from, seed, 0.1, 0.3);
    const CcdStepResult ref = continuous_collisions_brute_force(from, to);
    ASSERT_GT(ref.vf.size() + ref.ee.size(), 0u) << "the object must fold onto itself";
    const CcdSweep sweep = CcdSweep::compute(from, to, 2);
    const CcdStepResult off = continuous_collisions(from, to, sweep, CcdOptions{2});
    CcdOptions opts{2};
    opts.voxel_backend = backend.get();
    const CcdStepResult r = continuous_collisions(from, to, sweep, opts);
    test::expect_same_ccd(r, ref);
    EXPECT_TRUE(r.stage2);
    EXPECT_EQ(r.counters.voxelized_triangles, 0u);
    EXPECT_FALSE(r.voxel_grid.has_value());
    EXPECT_EQ(r.counters.unshared_pairs, 0u);
    EXPECT_EQ(r.counters.elementary_tests(), off.counters.elementary_tests());
    EXPECT_GT(off.counters.elementary_tests(), 0u);
  }
  // Two folding objects that overlap along a strip: only triangles of pairs between them are
  // voxelized.
  Frame from = test::make_random_frame(71, 1, 1.0, 2);
  from.index = 0;
  Object other = from.objects[0];
  other.name = "other";
  const double width = [&] {
    AABB box;
    for (const Vec3& p : other.positions) box.extend(p);
    return (box.hi - box.lo).maxCoeff();
  }();
  for (Vec3& p : other.positions) p += Vec3(0.8 * width, 0, 0);
  from.objects.push_back(other);
  const Frame to = moved(from, 5, 0.02, 0.3);
  const CcdSweep sweep = CcdSweep::compute(from, to, 2);
  CcdOptions opts{2};
  opts.voxel_backend = backend.get();
  const CcdStepResult r = continuous_collisions(from, to, sweep, opts);
  test::expect_same_ccd(r, continuous_collisions_brute_force(from, to));
  const auto all = static_cast<std::uint64_t>(from.objects[0].num_triangles() + from.objects[1].num_triangles());
  EXPECT_GT(r.counters.voxelized_triangles, 0u);
  EXPECT_LT(4 * r.counters.voxelized_triangles, all) << r.counters.voxelized_triangles << " of " << all;
  std::printf("[          ] two objects: %llu of %llu triangles voxelized\n",
              static_cast<unsigned long long>(r.counters.voxelized_triangles), static_cast<unsigned long long>(all));
}

// Far from the origin the culling margin (it grows with the coordinates' magnitude) can
// exceed the triangles themselves; the default cell then grows with it. Sizing the cell by
// the triangles alone made every record's box millions of voxels at 2^42 (out of memory);
// at 2^33 it made them thousands. Here each record marks a bounded number of voxels and the
// results equal the brute force.
/// A random step of 3 small objects moved by 2^33 along x (or not), and its triangle count.
struct OffsetStep {
  Frame from, to;
  std::size_t triangles = 0;
  explicit OffsetStep(double offset) : from(test::make_random_frame(3, 3, 2.0, 1)) {
    for (Object& o : from.objects) {
      for (Vec3& p : o.positions) p += Vec3(offset, 0, 0);
      triangles += static_cast<std::size_t>(o.num_triangles());
    }
    from.index = 0;
    to = moved(from, 5, 0.6, 0.1);
  }
};

TEST(CcdStage2, DefaultCellAllowsForAMarginLargerThanTheTriangles) {
  const OffsetStep step(std::ldexp(1.0, 33));
  const auto& [from, to, triangles] = step;
  const CcdSweep sweep = CcdSweep::compute(from, to, 2);
  ASSERT_GT(sweep.margin, 0.5) << sweep.margin;  // larger than the scene's triangles (edges ~0.3-0.5)
  const CcdVoxelCulling voxels(from, to, sweep, 0, 2);
  const std::size_t records = triangles * static_cast<std::size_t>(voxels.slots());
  EXPECT_LE(voxels.marked_voxels(), 200 * records) << voxels.marked_voxels() << " marks, " << records << " records";
  const CcdStepResult ref = continuous_collisions_brute_force(from, to);
  test::expect_same_ccd(continuous_collisions(from, to, sweep, CcdOptions{2, &voxels}), ref);
}

// The same with the grid given (--grid): it is honoured unless the records would cover
// thousands of voxels each. Far from the origin the margin dwarfs the triangles, and a fine
// grid made every record cover ~N^3 voxels: --grid 128 took over 60 s and 19 GB on a small
// scene at 1e12, 200 ran out of memory.
TEST(CcdStage2, GivenGridIsCoarsenedWhereTheMarginDwarfsTheTriangles) {
  const OffsetStep step(std::ldexp(1.0, 33));
  const auto& [from, to, triangles] = step;
  const CcdSweep sweep = CcdSweep::compute(from, to, 2);
  const CcdStepResult ref = continuous_collisions_brute_force(from, to);
  for (int grid : {16, 200, 4096}) {
    SCOPED_TRACE("grid " + std::to_string(grid));
    const CcdVoxelCulling voxels(from, to, sweep, grid, 2);
    const std::size_t records = triangles * static_cast<std::size_t>(voxels.slots());
    EXPECT_LE(voxels.marked_voxels(), 6000 * records) << voxels.marked_voxels() << " marks, " << records << " records";
    test::expect_same_ccd(continuous_collisions(from, to, sweep, CcdOptions{2, &voxels}), ref);
  }
  // Near the origin a grid of 16 is what it says: the bound does not bite.
  const OffsetStep near(0);
  const CcdVoxelCulling given(near.from, near.to, CcdSweep::compute(near.from, near.to, 2), 16, 2);
  EXPECT_EQ(std::max({given.grid().dims[0], given.grid().dims[1], given.grid().dims[2]}), 17);
}

}  // namespace
}  // namespace vproxq
