// The self Stage II on the GPU (gl/self_voronoi_backend, shaders/dvd_self_gather.comp):
// per-sample agreement with the CPU twin within the two error bounds, Lemma 2's bounds, and the
// intra-object query with every backend (off, cpu, gpu) equal to the brute force, per triangle
// and bitwise, on generated meshes and on the test meshes (bunny, height field, thick cloth).
#include <gtest/gtest.h>
#include "core/voronoi/bins.hpp"
#include <random>
#include <iostream>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>

#include "core/broad_phase/object_broad_phase.hpp"
#include "core/query/intra_distance.hpp"
#include "core/voronoi/self_stage2.hpp"
#include "gl/self_voronoi_backend.hpp"
#include "gl_test_support.hpp"
#include "io/scene_source.hpp"
#include "support/self_meshes.hpp"

namespace vproxq::gl {
namespace {

using test::expect_same_intra;

/// Runs the GL backend and the CPU twin on the same input, and returns the GL result.
class Twin final : public SelfVoronoiBackend {
 public:
  explicit Twin(const Context& context, const GlVoronoiOptions& options = {})
      : gpu(context, options), cpu(make_cpu_self_voronoi_backend(2)) {}
  std::string name() const override { return "gpu"; }
  std::string device() const override { return gpu.device(); }
  double distance_error_bound(double extent) const override { return gpu.distance_error_bound(extent); }
  SelfDvdOutput compute(const SelfDvdInput& in) override {
    input = in;
    cpu_out = cpu->compute(in);
    gpu_out = gpu.compute(in);
    return gpu_out;
  }
  GlSelfVoronoiBackend gpu;
  std::unique_ptr<SelfVoronoiBackend> cpu;
  SelfDvdInput input;
  SelfDvdOutput cpu_out, gpu_out;
};

/// Largest |coordinate| relative to the grid origin (E of the error bounds).
double extent_of(const DvdInput& in) {
  double e = in.grid.cell * *std::max_element(in.grid.dims.begin(), in.grid.dims.end());
  for (const double c : in.tri_xyz_d) e = std::max(e, std::abs(c));
  return e;
}

/// Every sample: GL and CPU values (capped at the band) within the sum of their error bounds.
void expect_twin_agreement(const Twin& twin) {
  const DvdInput& in = twin.input.dvd;
  const double e = extent_of(in);
  const double tol = twin.gpu.distance_error_bound(e) + twin.cpu->distance_error_bound(e);
  ASSERT_EQ(twin.gpu_out.dist.size(), in.voxels.size());
  ASSERT_EQ(twin.cpu_out.dist.size(), in.voxels.size());
  int bad = 0;
  for (size_t k = 0; k < in.voxels.size(); ++k) {
    const double band = in.band[k];
    const double g = std::min<double>(twin.gpu_out.dist[k], band);
    const double c = std::min<double>(twin.cpu_out.dist[k], band);
    if (std::abs(g - c) > tol && ++bad <= 5)
      ADD_FAILURE() << "sample " << k << ": gpu " << g << " cpu " << c << " band " << band;
    // The reported triangle is a real non-adjacent triangle of the same object.
    const std::int32_t t = twin.gpu.last_nearest()[k];
    if (t == kNoIndex) continue;
    const auto f = static_cast<size_t>(twin.input.sample_triangle[k]);
    EXPECT_EQ(in.tri_site[static_cast<size_t>(t)], in.tri_site[f]);
    for (int a = 0; a < 3; ++a)
      for (int b = 0; b < 3; ++b)
        EXPECT_NE(twin.input.tri_vertices[3 * f + static_cast<size_t>(a)],
                  twin.input.tri_vertices[3 * static_cast<size_t>(t) + static_cast<size_t>(b)]);
  }
  EXPECT_EQ(bad, 0);
}

/// Off, cpu and gpu Stage III against the brute force; with the gpu: Lemma 2 per triangle
/// and the per-sample agreement with the CPU twin. `grids`: resolutions to try (0: default).
void check_all_backends(const Context& context, const Frame& frame, const std::string& what,
                        std::initializer_list<int> grids, bool brute_force = true) {
  // The sorted scan equals the brute force (tests/core/test_intra_distance.cpp) and is fast
  // enough for the test meshes.
  const auto ref = brute_force ? intra_object_distance_brute_force(frame, 2)
                               : intra_object_distance_sorted_scan(frame, 2);
  const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
  const auto ring2 = ring2_upper_bounds(frame, 2);
  expect_same_intra(intra_object_distance(frame, boxes, ring2, {2}), ref, what + ", off");
  auto cpu = make_cpu_self_voronoi_backend(2);
  Twin twin(context, GlVoronoiOptions{64, 97});  // small batches: several dispatches
  for (int grid : grids) {
    const std::string at = what + ", grid " + std::to_string(grid);
    const SelfVoronoiBounds cb = compute_self_voronoi_bounds(frame, boxes, ring2, *cpu, grid, 2);
    expect_same_intra(intra_object_distance(frame, boxes, ring2, {2, &cb}), ref, at + ", cpu");
    const SelfVoronoiBounds gb = compute_self_voronoi_bounds(frame, boxes, ring2, twin, grid, 2);
    expect_twin_agreement(twin);
    for (size_t i = 0; i < frame.objects.size(); ++i)
      for (size_t t = 0; t < ref.per_object[i].per_triangle.size(); ++t) {
        const double sd = ref.per_object[i].per_triangle[t].distance;
        ASSERT_LE(gb.triangle_lower[i][t], sd) << at << " object " << i << " triangle " << t;
        ASSERT_GE(gb.triangle_upper[i][t], sd) << at << " object " << i << " triangle " << t;
      }
    expect_same_intra(intra_object_distance(frame, boxes, ring2, {2, &gb}), ref, at + ", gpu");
  }
}

// Samples whose bins hold more triangles than one invocation may loop over on some drivers
// (llvmpipe stops an invocation's loops after 65535 iterations in all, silently): 70,000
// small triangles of one object around a few samples. The shader reports the samples it could
// not finish and the backend computes them on the CPU, so they agree with the CPU twin.
TEST(GlSelfVoronoi, SamplesBeyondADriversLoopCapAgreeWithTheCpu) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  SelfDvdInput in;
  DvdInput& d = in.dvd;
  d.grid.origin = Vec3(0, 0, 0);
  d.grid.cell = 0.25;
  d.grid.dims = {8, 8, 8};
  std::mt19937 rng(71);
  std::uniform_real_distribution<double> unit(0.8, 1.2);
  for (std::int32_t t = 0; t < 70000; ++t) {
    const Vec3 a{unit(rng), unit(rng), unit(rng)};
    for (const Vec3& c : {a, Vec3(a + Vec3(0.01, 0, 0)), Vec3(a + Vec3(0, 0.01, 0.003))})
      for (int k = 0; k < 3; ++k) {
        d.tri_xyz_d.push_back(c[k]);
        d.tri_xyz.push_back(static_cast<float>(c[k]));
      }
    d.tri_site.push_back(0);
    for (std::int32_t v = 0; v < 3; ++v) in.tri_vertices.push_back(3 * t + v);
  }
  for (std::int64_t v : {0, 73, 146, 292, 365, 511}) {
    d.voxels.push_back(v);
    d.band.push_back(2.0f);
    in.sample_triangle.push_back(static_cast<std::int32_t>(v));
  }
  bin_triangles(d, 4);
  Twin twin(context);
  twin.compute(in);
  expect_twin_agreement(twin);
  std::cout << "70,000 triangles near 6 samples: " << twin.gpu.last_redone()
            << " samples computed on the CPU (loop cap)\n";
}

TEST(GlSelfVoronoi, GeneratedMeshesAllBackendsEqualBruteForce) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    test::Rng rng(seed);
    Frame frame;
    frame.objects.push_back(test::make_folded_sheet(rng, 20, 8, 0.1, 0.03 * static_cast<double>(seed), 0.1));
    frame.objects.push_back(test::make_irregular_mesh(rng));
    frame.objects.push_back(test::make_blob(rng, Vec3(3, 0, 0), 1.0, 2, 0.5, "blob"));
    frame.objects.push_back(test::make_soup(rng, Vec3(0, 3, 0), 0.5, 0.3, 40, "soup"));
    check_all_backends(context, frame, "generated seed " + std::to_string(seed), {8, 40, 0});
  }
}

TEST(GlSelfVoronoi, TestMeshesAllBackendsEqualBruteForce) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  const std::filesystem::path dir = std::filesystem::path(VPROXQ_TEST_DATA_DIR) / "meshes";
  for (const char* file : {"bunny-npm.obj", "height-field.ply", "thick-cloth/t0.ply", "thick-cloth/t1.ply"}) {
    const Frame frame = SceneSource::open(dir / file).load_frame(0);
    check_all_backends(context, frame, file, {0}, /*brute_force=*/frame.objects[0].num_triangles() < 1000);
  }
}

}  // namespace
}  // namespace vproxq::gl
