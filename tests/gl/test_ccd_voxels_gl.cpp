// The GL backend of CCD Stage II (gl/ccd_voxel_backend, shaders/ccd_voxels.comp) against the
// voxel-by-voxel reference and the CPU backend: integer work, so everything must be equal —
// keys, counts, co-occupancy flags, and the culling decisions and results of the pipeline.
#include <gtest/gtest.h>

#include <initializer_list>
#include <iostream>

#include "core/query/ccd.hpp"
#include "core/voronoi/ccd_stage2.hpp"
#include "gl/ccd_voxel_backend.hpp"
#include "gl_test_support.hpp"
#include "support/ccd_voxels.hpp"
#include "support/expect_same.hpp"
#include "support/random_scene.hpp"

namespace vproxq::gl {
namespace {

// Each GL backend's output for `in` against the reference and the CPU backend's output `c`
// (and that no backend redid the input on the CPU).
void expect_gl_backends_match(const CcdVoxelInput& in, const CcdVoxelOutput& c,
                              std::initializer_list<GlCcdVoxelBackend*> backends) {
  for (GlCcdVoxelBackend* b : backends) {
    const CcdVoxelOutput g = b->voxelize(in);
    test::expect_ccd_output_matches_reference(in, g);
    EXPECT_EQ(g.counts, c.counts);
    EXPECT_EQ(g.foreign, c.foreign);
    EXPECT_FALSE(b->last_fell_back());
  }
}

TEST(CcdVoxelsGl, RandomRecordsEqualTheReferenceAndTheCpu) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  GlCcdVoxelBackend gpu(context);
  GlCcdVoxelBackend small_batches(context, GlCcdVoxelOptions{32, 4096});
  const auto cpu = make_cpu_ccd_voxel_backend(2);
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    CcdVoxelInput in = test::random_ccd_voxel_input(seed, {6 + static_cast<int>(seed), 8, 5}, 4, 500);
    in.cooccupancy = seed % 3 != 0;
    expect_gl_backends_match(in, cpu->voxelize(in), {&gpu, &small_batches});
    EXPECT_GT(small_batches.last_batch_count(), 1u);
  }
}

// The backend keeps its buffers from one call to the next (growing only): calls of every size
// order, with and without co-occupancy and in one or many batches, each give what a fresh CPU
// backend gives. A table, key room or count left over from a larger call must not show.
TEST(CcdVoxelsGl, BuffersKeptFromCallToCallGiveTheSameOutputAsFreshOnes) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  GlCcdVoxelBackend gpu(context);
  GlCcdVoxelBackend small_batches(context, GlCcdVoxelOptions{32, 4096});
  const auto cpu = make_cpu_ccd_voxel_backend(2);
  struct Call {
    std::array<std::int32_t, 3> dims;
    int records;
    bool cooccupancy;
  };
  const Call calls[] = {{{12, 10, 9}, 800, true}, {{5, 4, 3}, 30, true},   {{12, 10, 9}, 800, true},
                        {{6, 6, 6}, 200, false},  {{9, 7, 8}, 1200, true}, {{4, 4, 4}, 1, true},
                        {{7, 7, 7}, 300, true}};
  std::uint64_t seed = 100;
  for (const Call& call : calls) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    CcdVoxelInput in = test::random_ccd_voxel_input(seed++, call.dims, 3, call.records);
    in.cooccupancy = call.cooccupancy;
    expect_gl_backends_match(in, cpu->voxelize(in), {&gpu, &small_batches});
  }
}

// Records whose boxes hold more voxels than one invocation may loop over on some drivers
// (llvmpipe stops every loop of an invocation after 65535 iterations in all): the output still
// equals the reference, the shader reporting the boxes it could not finish and the backend
// redoing the input on the CPU. A fine grid on a scene of a few large triangles made such
// records and lost contacts before.
TEST(CcdVoxelsGl, BoxesBeyondADriversLoopCapEqualTheReference) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  GlCcdVoxelBackend gpu(context);
  const auto cpu = make_cpu_ccd_voxel_backend(2);
  CcdVoxelInput in = test::random_ccd_voxel_input(7, {48, 48, 48}, 2, 40);
  // Two records spanning 48 x 48 x 40 = 92,160 voxels each, of two objects, cut by one plane.
  for (int r = 0; r < 2; ++r) {
    CcdVoxelRecord& rec = in.records[static_cast<size_t>(r)];
    rec.lo = {0, 0, r * 8};
    rec.hi = {47, 47, 39 + r * 8};
    rec.axis = {{{1, 1, 1}, {0, 0, 0}, {0, 0, 0}}};
    rec.below = {20, -1, -1};
    rec.above = {200, 1, 1};
    in.record_object[static_cast<size_t>(r)] = r;
  }
  in.out_offsets.assign(in.records.size() + 1, 0);
  for (size_t r = 0; r < in.records.size(); ++r) {
    const auto& rec = in.records[r];
    std::uint64_t volume = 1;
    for (int k = 0; k < 3; ++k) volume *= static_cast<std::uint64_t>(rec.hi[k] - rec.lo[k] + 1);
    in.out_offsets[r + 1] = in.out_offsets[r] + volume;
  }
  const CcdVoxelOutput g = gpu.voxelize(in);
  test::expect_ccd_output_matches_reference(in, g);
  const CcdVoxelOutput c = cpu->voxelize(in);
  EXPECT_EQ(g.counts, c.counts);
  EXPECT_EQ(g.foreign, c.foreign);
  EXPECT_GT(c.counts[0], 65535u);
  std::cout << "GL CCD voxels on " << context.info().gl_renderer
            << (gpu.last_fell_back() ? ": redone on the CPU (loop cap)\n" : ": finished on the GPU\n");
}

TEST(CcdVoxelsGl, PipelineCullingEqualsTheCpuBackend) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  GlCcdVoxelBackend gpu(context);
  const auto cpu = make_cpu_ccd_voxel_backend(2);
  for (std::uint64_t seed = 1; seed <= 3; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    test::Rng rng(seed * 101);
    const Frame from = test::make_random_frame(seed, 5, 3.0, 1);
    Frame to = from;
    to.index = 1;
    for (Object& o : to.objects) {
      const Vec3 d = rng.vec3(-0.6, 0.6);
      for (Vec3& p : o.positions) p += d + rng.vec3(-0.2, 0.2);
    }
    const CcdSweep sweep = CcdSweep::compute(from, to, 2);
    const CcdStepResult ref = continuous_collisions_brute_force(from, to);
    for (int grid : {0, 20}) {
      const CcdVoxelCulling a(from, to, sweep, CcdVoxelOptions{grid, 4, 2}, *cpu);
      const CcdVoxelCulling b(from, to, sweep, CcdVoxelOptions{grid, 4, 2}, gpu);
      ASSERT_EQ(a.marked_voxels(), b.marked_voxels());
      std::size_t kept = 0, total = 0;
      for (Index o = 0; o < static_cast<Index>(from.objects.size()); ++o)
        for (Index t = 0; t < from.objects[static_cast<size_t>(o)].num_triangles(); ++t) {
          ASSERT_EQ(a.keys(o, t), b.keys(o, t));
          ASSERT_EQ(a.keeps(o, t), b.keeps(o, t));
          kept += a.keeps(o, t);
          ++total;
        }
      EXPECT_GT(kept, 0u);
      EXPECT_LT(kept, total);  // co-occupancy culls something, or the check proves little
      const CcdStepResult ra = continuous_collisions(from, to, sweep, CcdOptions{2, &a});
      const CcdStepResult rb = continuous_collisions(from, to, sweep, CcdOptions{2, &b});
      EXPECT_EQ(ra.counters.triangle_pairs, rb.counters.triangle_pairs);
      EXPECT_EQ(ra.counters.elementary_tests(), rb.counters.elementary_tests());
      EXPECT_EQ(ra.counters.culled_triangles, rb.counters.culled_triangles);
      ASSERT_EQ(rb.vf.size(), ref.vf.size());
      ASSERT_EQ(rb.ee.size(), ref.ee.size());
      for (size_t k = 0; k < ref.vf.size(); ++k) EXPECT_EQ(rb.vf[k].toi, ref.vf[k].toi);
      for (size_t k = 0; k < ref.ee.size(); ++k) EXPECT_EQ(rb.ee[k].toi, ref.ee[k].toi);
    }
  }
}

// Stage II built inside continuous_collisions() over the candidate pairs' triangles: the GL
// backend gives the CPU's culling, counter for counter, and the brute force's answers.
TEST(CcdVoxelsGl, StageIIOverTheCandidatePairsEqualsTheCpuBackend) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  GlCcdVoxelBackend gpu(context);
  const auto cpu = make_cpu_ccd_voxel_backend(2);
  std::uint64_t unshared = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    const Frame from = test::make_random_frame(seed + 40, 5, 3.0, 1);
    const Frame to = test::moved(from, seed * 7, 0.8, seed % 2 ? 0.25 : 0.05);
    const CcdSweep sweep = CcdSweep::compute(from, to, 2);
    const CcdStepResult ref = continuous_collisions_brute_force(from, to);
    for (int slots : {2, 8}) {
      for (int grid : {0, 50}) {
        SCOPED_TRACE("slots " + std::to_string(slots) + " grid " + std::to_string(grid));
        CcdOptions a{2}, b{2};
        a.voxel_backend = cpu.get();
        b.voxel_backend = &gpu;
        a.voxel_grid = b.voxel_grid = grid;
        a.voxel_slots = b.voxel_slots = slots;
        const CcdStepResult ra = continuous_collisions(from, to, sweep, a);
        const CcdStepResult rb = continuous_collisions(from, to, sweep, b);
        ASSERT_TRUE(ra.voxel_grid && rb.voxel_grid);
        EXPECT_EQ(*ra.voxel_grid, *rb.voxel_grid);
        EXPECT_EQ(ra.counters.voxelized_triangles, rb.counters.voxelized_triangles);
        EXPECT_GT(ra.counters.voxelized_triangles, 0u);
        EXPECT_EQ(ra.counters.unshared_pairs, rb.counters.unshared_pairs);
        EXPECT_EQ(ra.counters.culled_triangles, rb.counters.culled_triangles);
        EXPECT_EQ(ra.counters.elementary_tests(), rb.counters.elementary_tests());
        unshared += ra.counters.unshared_pairs;
        test::expect_same_ccd(rb, ref);
      }
    }
  }
  EXPECT_GT(unshared, 0u);  // the culling runs, or the comparison proves little
}

}  // namespace
}  // namespace vproxq::gl
