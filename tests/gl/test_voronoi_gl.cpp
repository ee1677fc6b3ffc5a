// The GL Stage II backend (gl/voronoi_backend, shaders/dvd2_gather.comp) against a double
// reference and against the CPU backend.
//
// Property checked everywhere: every reported distance is within
// GlVoronoiBackend::distance_error_bound(E) of the exact one (E: largest |coordinate| of the
// input, relative to the grid origin), and every reported site is one whose exact distance is
// within twice that bound of the right answer, so the sites are the reference's wherever the
// gap between candidates exceeds 2x the bound. The double reference (core point_triangle
// distance, ~2^-53 relative) counts as exact: the bound is ~2^-14 E.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <string>
#include <vector>

#include "core/geometry/point_triangle.hpp"
#include "core/voronoi/bins.hpp"
#include "core/voronoi/discrete_voronoi.hpp"
#include "support/dvd_input.hpp"
#include "gl/voronoi_backend.hpp"
#include "gl_test_support.hpp"

namespace vproxq::gl {
namespace {

using test::sample_point;
using test::triangle_of;

/// Adds a triangle given in absolute coordinates: relative to the origin in double, then
/// rounded to float, as the host does.
void add_triangle(DvdInput& in, const Triangle& absolute, std::int32_t site) {
  for (const Vec3& c : absolute) {
    for (int k = 0; k < 3; ++k) {
      const double relative = c[k] - in.grid.origin[k];
      in.tri_xyz_d.push_back(relative);
      in.tri_xyz.push_back(static_cast<float>(relative));
    }
  }
  in.tri_site.push_back(site);
}

/// E of the error bound: every triangle corner and sample point is within [-E, E]^3.
double extent_of(const DvdInput& in) {
  double e = in.grid.cell * *std::max_element(in.grid.dims.begin(), in.grid.dims.end());
  for (const double c : in.tri_xyz_d) e = std::max(e, std::abs(c));
  return e;
}

/// Per sample voxel: every site's exact minimum distance, capped at the band.
struct Reference {
  std::vector<std::map<std::int32_t, double>> site_distance;  // [voxel]: sites below the band
  std::vector<double> first, second;                          // two smallest (capped) values
  std::vector<double> runner_up;  // the second smallest even where only the nearest is asked for
  std::vector<std::int32_t> site1, site2;                     // their sites (kNoIndex when >= band)
};

/// With `use_bins`, only the triangles of bins_within(sample, band) are evaluated: exact by the
/// binning tests (tests/core/test_voronoi_cpu.cpp), and much faster for large inputs.
Reference reference(const DvdInput& in, bool use_bins = false) {
  Reference ref;
  for (std::size_t k = 0; k < in.voxels.size(); ++k) {
    const Vec3 q = sample_point(in.grid, in.voxels[k]);
    const double band = in.band[k];
    std::map<std::int32_t, double> best;
    const std::int32_t skip = in.exclude_site.empty() ? kNoIndex : in.exclude_site[k];
    auto consider = [&](std::size_t t) {
      if (in.tri_site[t] == skip) return;
      const double d = std::sqrt(point_triangle_distance(q, triangle_of(in, t)).squared_distance);
      if (d >= band) return;
      const auto [it, inserted] = best.emplace(in.tri_site[t], d);
      if (!inserted) it->second = std::min(it->second, d);
    };
    if (use_bins) {
      const BinRange range = bins_within(in, q, band);
      for (std::int32_t z = range.lo[2]; z <= range.hi[2]; ++z)
        for (std::int32_t y = range.lo[1]; y <= range.hi[1]; ++y)
          for (std::int32_t x = range.lo[0]; x <= range.hi[0]; ++x) {
            const auto b = static_cast<std::size_t>(bin_id(in, x, y, z));
            for (std::int32_t i = in.bin_offsets[b]; i < in.bin_offsets[b + 1]; ++i) {
              consider(static_cast<std::size_t>(in.bin_tris[static_cast<std::size_t>(i)]));
            }
          }
    } else {
      for (std::size_t t = 0; t < in.tri_site.size(); ++t) consider(t);
    }
    std::vector<std::pair<double, std::int32_t>> order;
    for (const auto& [s, d] : best) order.emplace_back(d, s);
    std::sort(order.begin(), order.end());
    auto value = [&](std::size_t i) { return i < order.size() ? order[i].first : band; };
    auto site = [&](std::size_t i) { return i < order.size() ? order[i].second : kNoIndex; };
    ref.first.push_back(value(0));
    // With an excluded site only the nearest is asked for: no second site.
    ref.second.push_back(skip == kNoIndex ? value(1) : band);
    ref.runner_up.push_back(value(1));
    ref.site1.push_back(site(0));
    ref.site2.push_back(skip == kNoIndex ? site(1) : kNoIndex);
    ref.site_distance.push_back(std::move(best));
  }
  return ref;
}

/// |a - b|, and 0 when both are the same infinity (an infinite band is reported as is).
double gap(double a, double b) { return a == b ? 0.0 : std::abs(a - b); }

struct CheckStats {
  double max_ratio = 0;               // max |error| / bound over all reported distances
  std::int64_t values = 0;            // distances checked
  std::int64_t site_differences = 0;  // sites differing from the reference (near ties)
};

/// Checks `got` against the reference (see the file comment) and accumulates statistics.
void check_against_reference(const DvdInput& in, const Reference& ref, const DvdOutput& got,
                             double bound, CheckStats& stats) {
  ASSERT_EQ(got.site1.size(), in.voxels.size());
  int failures = 0;
  for (std::size_t k = 0; k < in.voxels.size() && failures < 10; ++k) {
    const double band = in.band[k];
    auto exact = [&](std::int32_t site) {
      const auto it = ref.site_distance[k].find(site);
      return it == ref.site_distance[k].end() ? band : it->second;  // also for kNoIndex
    };
    const double e1 = gap(got.dist1[k], ref.first[k]);
    const double e2 = gap(got.dist2[k], ref.second[k]);
    stats.max_ratio = std::max({stats.max_ratio, e1 / bound, e2 / bound});
    stats.values += 2;
    stats.site_differences += (got.site1[k] != ref.site1[k]) + (got.site2[k] != ref.site2[k]);
    const bool ok = e1 <= bound && e2 <= bound && gap(exact(got.site1[k]), ref.first[k]) <= 2 * bound &&
                    gap(exact(got.site2[k]), ref.second[k]) <= 2 * bound &&
                    (got.site1[k] != got.site2[k] || got.site1[k] == kNoIndex) &&
                    (got.site1[k] != kNoIndex || got.site2[k] == kNoIndex) &&
                    (ref.runner_up[k] - ref.first[k] <= 2 * bound || got.site1[k] == ref.site1[k]);
    if (!ok) {
      ++failures;
      ADD_FAILURE() << "voxel " << in.voxels[k] << " (band " << band << ", bound " << bound
                    << "): GPU sites " << got.site1[k] << ", " << got.site2[k] << " at "
                    << got.dist1[k] << ", " << got.dist2[k] << "; reference " << ref.site1[k]
                    << ", " << ref.site2[k] << " at " << ref.first[k] << ", " << ref.second[k];
    }
  }
}

struct SceneOptions {
  int sites = 10;
  int triangles = 500;
  int voxels = 3000;
  double max_band_cells = 6;
  Vec3 origin = Vec3(-20000.5, 35000.25, 1e5);
  double cell = 0.37;
  std::array<std::int32_t, 3> dims{48, 40, 36};
};

/// Random triangles of several sites, in absolute coordinates far from 0 (only the relative
/// ones reach the backends). Mixed in: degenerate triangles, slivers, large triangles, and
/// near-tied sites: copies of a triangle in another site, moved by ~1e-6 cell or not at all.
DvdInput random_scene(unsigned seed, const SceneOptions& options) {
  std::mt19937 rng(seed);
  DvdInput in;
  in.grid.origin = options.origin;
  in.grid.cell = options.cell;
  in.grid.dims = options.dims;
  const Vec3 size = in.grid.cell * Vec3(in.grid.dims[0], in.grid.dims[1], in.grid.dims[2]);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto inside = [&](const Vec3& relative) -> Vec3 {
    return in.grid.origin + relative.cwiseMax(Vec3::Zero()).cwiseMin(size);
  };
  auto jitter = [&](double scale) -> Vec3 {
    return scale * Vec3{unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5};
  };
  std::vector<Vec3> centres;
  for (int s = 0; s < options.sites; ++s) {
    centres.push_back(Vec3{unit(rng), unit(rng), unit(rng)}.cwiseProduct(size));
  }
  std::uniform_int_distribution<int> pick_site(0, options.sites - 1);
  for (int i = 0; i < options.triangles; ++i) {
    const int site = pick_site(rng);
    const Vec3 a = centres[static_cast<std::size_t>(site)] + jitter(10 * options.cell);
    Triangle t{inside(a), inside(a + jitter(4 * options.cell)),
               inside(a + jitter(4 * options.cell))};
    switch (i % 19) {
      case 2:  // two equal corners
        t[2] = t[1];
        break;
      case 5:  // a point
        t[1] = t[2] = t[0];
        break;
      case 8:  // collinear (up to rounding)
        t[2] = t[0] + 0.375 * (t[1] - t[0]);
        break;
      case 11:  // a cap: apex 1e-5 cell off the longest edge
        t[2] = 0.5 * (t[0] + t[1]) + 1e-5 * options.cell * Vec3(0.3, -0.8, 0.52);
        break;
      case 14:  // a large triangle
        t[1] = inside(a + jitter(30 * options.cell));
        t[2] = inside(a + jitter(30 * options.cell));
        break;
      default:
        break;
    }
    add_triangle(in, t, site);
    if (i % 7 == 3) {  // a near tie in another site
      Triangle copy = t;
      if (i % 14 == 3) {
        for (Vec3& c : copy) c += jitter(2e-6 * options.cell);
      }
      add_triangle(in, copy, (site + 1 + pick_site(rng)) % options.sites);
    }
  }
  std::set<std::int64_t> ids;
  std::uniform_int_distribution<std::int64_t> pick_voxel(0, in.grid.voxel_count() - 1);
  while (static_cast<int>(ids.size()) < options.voxels) ids.insert(pick_voxel(rng));
  in.voxels.assign(ids.begin(), ids.end());
  for (std::size_t k = 0; k < in.voxels.size(); ++k) {
    float band = static_cast<float>(unit(rng) * options.max_band_cells * in.grid.cell);
    if (k % 97 == 0) band = 0.0f;
    if (k % 89 == 1) band = std::numeric_limits<float>::infinity();
    in.band.push_back(band);
    // Every third voxel ignores one site (as Stage II does for a voxel of a single object).
    in.exclude_site.push_back(k % 3 == 0 ? pick_site(rng) : kNoIndex);
  }
  bin_triangles(in, 4);
  return in;
}

TEST(GlVoronoi, NameDeviceAndErrorBound) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  const GlVoronoiBackend backend(context);
  EXPECT_EQ(backend.name(), "gpu");
  EXPECT_EQ(backend.device(), context.renderer());
  EXPECT_FALSE(backend.device().empty());
  EXPECT_DOUBLE_EQ(backend.distance_error_bound(8.0),
                   GlVoronoiBackend::kFloat32ErrorUnits * 0x1p-24 * 8.0 + 0x1p-48);
  std::cout << "shader compile " << backend.compile_ms() << " ms on " << backend.device() << "\n";
}

TEST(GlVoronoi, MatchesDoubleReferenceOnRandomScenes) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  GlVoronoiBackend backend(context);
  CheckStats stats;
  for (unsigned seed : {1u, 2u, 3u, 4u}) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    const DvdInput in = random_scene(seed, {});
    const double bound = backend.distance_error_bound(extent_of(in));
    check_against_reference(in, reference(in), backend.compute(in), bound, stats);
  }
  std::cout << stats.values << " distances: max |GPU - exact| / bound = " << stats.max_ratio
            << "; sites differing from the reference (near ties): " << stats.site_differences
            << "\n";
  RecordProperty("max_error_over_bound", std::to_string(stats.max_ratio));
}

/// `in` with its triangles listed in site order (stable) and binned again: as Stage II lists
/// them (object order), so that each excluded site's triangles are one run per bin, which the
/// shader passes over by binary search instead of entry by entry.
DvdInput in_site_order(const DvdInput& in) {
  std::vector<std::size_t> order(in.tri_site.size());
  for (std::size_t t = 0; t < order.size(); ++t) order[t] = t;
  std::stable_sort(order.begin(), order.end(), [&](std::size_t a, std::size_t b) { return in.tri_site[a] < in.tri_site[b]; });
  DvdInput sorted = in;
  sorted.tri_xyz.clear();
  sorted.tri_xyz_d.clear();
  sorted.tri_site.clear();
  for (const std::size_t t : order) {
    sorted.tri_xyz.insert(sorted.tri_xyz.end(), in.tri_xyz.begin() + 9 * static_cast<std::ptrdiff_t>(t),
                          in.tri_xyz.begin() + 9 * static_cast<std::ptrdiff_t>(t + 1));
    sorted.tri_xyz_d.insert(sorted.tri_xyz_d.end(), in.tri_xyz_d.begin() + 9 * static_cast<std::ptrdiff_t>(t),
                            in.tri_xyz_d.begin() + 9 * static_cast<std::ptrdiff_t>(t + 1));
    sorted.tri_site.push_back(in.tri_site[t]);
  }
  bin_triangles(sorted, in.bin_size);
  return sorted;
}

// With triangles in site order the shader passes over the excluded site's run of entries in
// each bin (a binary search, checked). Sites here are slabs along x, 1.5 cells thick, and each
// sample excludes its own slab, so the nearest other site is often the slab beside it, whose
// triangles' ids border the run: a run one entry too long at either end would drop one of
// them. The answers must match the reference, computed on the GPU: a search that went wrong
// would be redone on the CPU (last_redone()).
TEST(GlVoronoi, TrianglesInSiteOrderMatchTheReference) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  GlVoronoiBackend backend(context);
  CheckStats stats;
  for (unsigned seed : {5u, 6u, 7u}) {
    SCOPED_TRACE(::testing::Message() << "seed " << seed);
    SceneOptions options;
    options.triangles = 2000;
    DvdInput in = random_scene(seed, options);
    const double slab = 1.5 * in.grid.cell;
    for (std::size_t t = 0; t < in.tri_site.size(); ++t) {
      const Triangle tri = triangle_of(in, t);
      const double x = (tri[0][0] + tri[1][0] + tri[2][0]) / 3;  // relative to the origin
      in.tri_site[t] = static_cast<std::int32_t>(std::clamp(std::floor(x / slab), 0.0, 1000.0));
    }
    for (std::size_t k = 0; k < in.voxels.size(); ++k) {
      const double x = sample_point(in.grid, in.voxels[k])[0];
      in.exclude_site[k] = k % 3 == 2 ? kNoIndex : static_cast<std::int32_t>(std::floor(x / slab));
    }
    in = in_site_order(in);
    const double bound = backend.distance_error_bound(extent_of(in));
    check_against_reference(in, reference(in), backend.compute(in), bound, stats);
    EXPECT_EQ(backend.last_redone(), 0u);
  }
  std::cout << stats.values << " distances: max |GPU - exact| / bound = " << stats.max_ratio << "\n";
}

TEST(GlVoronoi, AgreesWithCpuBackend) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  GlVoronoiBackend gpu(context);
  const auto cpu = make_cpu_voronoi_backend(2);
  const DvdInput in = random_scene(9, {});
  const DvdOutput g = gpu.compute(in);
  const DvdOutput c = cpu->compute(in);
  const double e = extent_of(in);
  const double tolerance = gpu.distance_error_bound(e) + cpu->distance_error_bound(e);
  int same_sites = 0;
  for (std::size_t k = 0; k < in.voxels.size(); ++k) {
    EXPECT_LE(gap(g.dist1[k], c.dist1[k]), tolerance) << k;
    EXPECT_LE(gap(g.dist2[k], c.dist2[k]), tolerance) << k;
    // The site must agree unless two sites are within the tolerance (only known without an
    // excluded site: with one, no second distance is reported).
    if (in.exclude_site[k] == kNoIndex && c.dist2[k] - c.dist1[k] > 2 * tolerance) {
      EXPECT_EQ(g.site1[k], c.site1[k]) << k;
    }
    same_sites += g.site1[k] == c.site1[k] && g.site2[k] == c.site2[k];
  }
  std::cout << same_sites << " of " << in.voxels.size() << " voxels with identical sites\n";
}

/// Awkward triangles placed around chosen sample points, one site each, far enough apart that
/// each sample point sees only its own triangle: caps of height 1 to 1e-9 of their length
/// (also exactly flat ones), needles, with the sample point on the plane, just above it, and
/// near an edge; coordinates up to ~250 cells from the origin.
TEST(GlVoronoi, SliversCapsAndNeedlesStayWithinTheBound) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  DvdInput in;
  in.grid.origin = Vec3(1e4, -2e4, 3e4);
  in.grid.cell = 1.0;
  in.grid.dims = {256, 256, 256};
  std::mt19937 rng(4242);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const double heights[] = {1.0, 1e-2, 1e-4, 1e-6, 1e-9, 0.0};
  const double offsets[] = {0.0, 1e-7, 1e-4, 0.3};  // sample point above the plane
  std::int32_t site = 0;
  for (int z = 2; z < 256; z += 5) {
    for (int y = 2; y < 256; y += 5) {
      for (int x = 2; x < 256; x += 5) {
        if (unit(rng) > 0.2) continue;
        const std::int64_t id = x + 256 * (y + std::int64_t{256} * z);
        const Vec3 q = in.grid.origin + sample_point(in.grid, id);
        // A random orthonormal frame.
        const Vec3 n = Vec3{unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5}.normalized();
        const Vec3 u1 = n.unitOrthogonal();
        const Vec3 u2 = n.cross(u1);
        auto at = [&](double s, double t, double h) -> Vec3 { return q + s * u1 + t * u2 - h * n; };
        const double length = 0.5 + unit(rng);
        const double height = heights[site % 6] * length;
        const double lift = offsets[(site / 6) % 4];
        const double shift = (unit(rng) - 0.5) * length;  // where along the edge the apex is
        Triangle t;
        switch ((site / 24) % 4) {
          case 0:  // cap (or flat): q projects inside, near the centroid
            t = {at(-0.5 * length, -height / 3, lift), at(0.5 * length, -height / 3, lift),
                 at(shift, 2 * height / 3, lift)};
            break;
          case 1:  // q projects just outside the long edge
            t = {at(-0.5 * length, 1e-6, lift), at(0.5 * length, 1e-6, lift),
                 at(shift, 1e-6 + height, lift)};
            break;
          case 2:  // needle: two corners 'height' apart, the third far
            t = {at(-0.5 * length, -0.1, lift), at(-0.5 * length + height, -0.1, lift),
                 at(0.5 * length, 0.2, lift)};
            break;
          default: {  // q past the tip of a needle 'height' wide, on its axis: within rounding
                      // of both long edges' lines (the case point_triangle.cpp's decide_face
                      // exists for), the tip 1e-6 .. 0.5 away
            const double gap = std::pow(10.0, -6.0 + 5.7 * unit(rng));
            t = {at(gap, 0.0, lift), at(gap + length, -0.5 * height, lift), at(gap + length, 0.5 * height, lift)};
            break;
          }
        }
        add_triangle(in, t, site++);
        in.voxels.push_back(id);
        in.band.push_back(1.9f);
      }
    }
  }
  bin_triangles(in, 4);
  GlVoronoiBackend backend(context);
  const double bound = backend.distance_error_bound(extent_of(in));
  CheckStats stats;
  check_against_reference(in, reference(in, /*use_bins=*/true), backend.compute(in), bound, stats);
  std::cout << in.voxels.size()
            << " awkward triangles: max |GPU - exact| / bound = " << stats.max_ratio << " (bound "
            << bound << ")\n";
  EXPECT_GT(in.voxels.size(), 1000u);
}

TEST(GlVoronoi, ManyBatchesCoverEveryVoxel) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  SceneOptions options;
  options.voxels = 12000;
  options.triangles = 300;
  const DvdInput in = random_scene(17, options);
  GlVoronoiOptions small;
  small.local_size = 32;
  small.max_groups_per_dispatch = 5;  // 160 voxels per dispatch: 75 dispatches
  GlVoronoiBackend batched(context, small);
  GlVoronoiBackend single(context);
  const DvdOutput a = batched.compute(in);
  EXPECT_EQ(batched.last_dispatch_count(), 75u);
  const DvdOutput b = single.compute(in);
  EXPECT_EQ(single.last_dispatch_count(), 1u);
  // Same shader, same data: identical, whatever the batching.
  EXPECT_EQ(a.site1, b.site1);
  EXPECT_EQ(a.site2, b.site2);
  EXPECT_EQ(a.dist1, b.dist1);
  EXPECT_EQ(a.dist2, b.dist2);
  CheckStats stats;
  check_against_reference(in, reference(in), a, batched.distance_error_bound(extent_of(in)), stats);
}

TEST(GlVoronoi, EmptyInputs) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  GlVoronoiBackend backend(context);
  DvdInput in;
  in.grid.dims = {4, 4, 4};
  bin_triangles(in, 4);
  EXPECT_TRUE(backend.compute(in).site1.empty());
  in.voxels = {0, 21, 63};
  in.band = {1.0f, 0.0f, std::numeric_limits<float>::infinity()};
  const DvdOutput out = backend.compute(in);  // no triangles at all
  ASSERT_EQ(out.site1.size(), 3u);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(out.site1[k], kNoIndex);
    EXPECT_EQ(out.site2[k], kNoIndex);
    EXPECT_EQ(out.dist1[k], in.band[k]);
    EXPECT_EQ(out.dist2[k], in.band[k]);
  }
}

// Sample voxels are handed to the shader by their coordinates, so grids of more than 2^32
// voxels work (fine --grid values on long scene boxes): triangles and samples in the far
// corner of a 4096 x 4096 x 512 grid (linear voxel ids above 1.9 * 2^32) match the reference.
TEST(GlVoronoi, GridsOfMoreThan2To32VoxelsMatchTheReference) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  GlVoronoiBackend backend(context);
  DvdInput in;
  in.grid.origin = Vec3(-3.5, 10.25, 7);
  in.grid.cell = 0.5;
  in.grid.dims = {4096, 4096, 512};
  std::mt19937 rng(33);
  std::uniform_real_distribution<double> unit(-1.0, 1.0);
  const Vec3 corner = in.grid.origin + in.grid.cell * Vec3(4090, 4090, 506);
  for (int t = 0; t < 30; ++t) {
    const Vec3 a = corner + 2.0 * Vec3{unit(rng), unit(rng), unit(rng)};
    add_triangle(in, {a, a + Vec3{unit(rng), unit(rng), unit(rng)}, a + Vec3{unit(rng), unit(rng), unit(rng)}}, t % 3);
  }
  for (std::int64_t z = 502; z < 510; ++z)
    for (std::int64_t y = 4086; y < 4094; ++y)
      for (std::int64_t x = 4086; x < 4094; ++x) {
        in.voxels.push_back(x + 4096 * (y + 4096 * z));
        in.band.push_back(3.0f);
        in.exclude_site.push_back(kNoIndex);
      }
  ASSERT_GT(in.voxels.front(), std::int64_t{1} << 32);
  bin_triangles(in, bin_size_for(in.grid, 4));
  CheckStats stats;
  check_against_reference(in, reference(in), backend.compute(in), backend.distance_error_bound(extent_of(in)), stats);
  EXPECT_GT(stats.values, 0);
}

// A sample whose bins hold more triangles than one invocation may loop over on some drivers
// (llvmpipe stops an invocation's loops after 65535 iterations in all, silently): 70,000
// triangles of 5 sites around a few sample voxels. The shader reports the samples it could not
// finish and the backend computes them on the CPU, so they still match the reference.
TEST(GlVoronoi, SamplesBeyondADriversLoopCapMatchTheReference) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  GlVoronoiBackend backend(context);
  DvdInput in;
  in.grid.origin = Vec3(1.5, -2, 0.25);
  in.grid.cell = 0.25;
  in.grid.dims = {8, 8, 8};
  std::mt19937 rng(70000);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  for (int t = 0; t < 70000; ++t) {
    const Vec3 a = in.grid.origin + Vec3{0.8 + 0.4 * unit(rng), 0.8 + 0.4 * unit(rng), 0.8 + 0.4 * unit(rng)};
    add_triangle(in, {a, a + Vec3(0.01, 0, 0), a + Vec3(0, 0.01, 0.003)}, t % 5);
  }
  for (std::int64_t v : {0, 9, 73, 146, 292, 365, 438, 511}) {
    in.voxels.push_back(v);
    in.band.push_back(2.0f);
    in.exclude_site.push_back(v % 2 == 0 ? kNoIndex : 1);
  }
  bin_triangles(in, 4);
  CheckStats stats;
  const DvdOutput got = backend.compute(in);
  check_against_reference(in, reference(in), got, backend.distance_error_bound(extent_of(in)), stats);
  std::cout << "70,000 triangles near 8 samples on " << backend.device() << ": " << backend.last_redone()
            << " samples computed on the CPU (loop cap)\n";
}

TEST(GlVoronoi, RejectsGridsTheShaderCannotAddress) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  GlVoronoiBackend backend(context);
  DvdInput in;
  in.grid.dims = {1 << 23, 1, 1};
  in.bin_size = 1 << 23;
  in.bin_dims = {1, 1, 1};
  in.bin_offsets = {0, 0};
  EXPECT_THROW(backend.compute(in), std::invalid_argument);
}

/// Objects made of lat-long spheres (320 triangles each, with degenerate pole triangles), the
/// sample voxels those triangles' boxes overlap, bands of ~3 cells: a Stage II-sized input.
DvdInput sphere_scene(int spheres, double radius_cells, int grid, unsigned seed) {
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  DvdInput in;
  in.grid.origin = Vec3(512.25, -1024.5, 77.0);
  in.grid.cell = 0.05;
  in.grid.dims = {grid, grid, grid};
  const double size = in.grid.cell * grid;
  const double r = radius_cells * in.grid.cell;
  constexpr int kSlices = 16, kStacks = 11;
  constexpr double kPi = 3.14159265358979323846;
  std::set<std::int64_t> voxels;
  for (int s = 0; s < spheres; ++s) {
    const Vec3 centre = in.grid.origin + Vec3::Constant(r + in.grid.cell) +
                        (size - 2 * (r + in.grid.cell)) * Vec3{unit(rng), unit(rng), unit(rng)};
    auto point = [&](int i, int j) -> Vec3 {
      const double phi = 2 * kPi * i / kSlices, theta = kPi * j / (kStacks - 1);
      return centre + r * Vec3(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                               std::cos(theta));
    };
    for (int i = 0; i < kSlices; ++i) {
      for (int j = 0; j + 1 < kStacks; ++j) {
        for (const Triangle& t : {Triangle{point(i, j), point(i + 1, j), point(i + 1, j + 1)},
                                  Triangle{point(i, j), point(i + 1, j + 1), point(i, j + 1)}}) {
          add_triangle(in, t, s);
          const std::size_t first = in.tri_xyz_d.size() - 9;
          std::array<std::int64_t, 3> lo{}, hi{};
          for (int k = 0; k < 3; ++k) {
            const double* c = &in.tri_xyz_d[first + static_cast<std::size_t>(k)];
            lo[static_cast<std::size_t>(k)] =
                static_cast<std::int64_t>(std::floor(std::min({c[0], c[3], c[6]}) / in.grid.cell));
            hi[static_cast<std::size_t>(k)] =
                static_cast<std::int64_t>(std::floor(std::max({c[0], c[3], c[6]}) / in.grid.cell));
          }
          for (std::int64_t z = lo[2]; z <= hi[2]; ++z)
            for (std::int64_t y = lo[1]; y <= hi[1]; ++y)
              for (std::int64_t x = lo[0]; x <= hi[0]; ++x)
                voxels.insert(x + grid * (y + grid * z));
        }
      }
    }
  }
  in.voxels.assign(voxels.begin(), voxels.end());
  for (std::size_t k = 0; k < in.voxels.size(); ++k) {
    in.band.push_back(static_cast<float>((3.0 + 0.5 * unit(rng)) * in.grid.cell));
  }
  bin_triangles(in, 4);
  return in;
}

TEST(GlVoronoi, SizeableSceneTimingsAgainstCpu) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  const DvdInput in = sphere_scene(110, 5.7, 128, 2006);
  GlVoronoiBackend gpu(context);
  const auto cpu = make_cpu_voronoi_backend(2);
  const DvdOutput g = gpu.compute(in);
  const DvdOutput c = cpu->compute(in);
  const double e = extent_of(in);
  const double tolerance = gpu.distance_error_bound(e) + cpu->distance_error_bound(e);
  double max_difference = 0;
  int near_ties = 0, with_second = 0;
  for (std::size_t k = 0; k < in.voxels.size(); ++k) {
    max_difference = std::max({max_difference, std::abs(double{g.dist1[k]} - c.dist1[k]),
                               std::abs(double{g.dist2[k]} - c.dist2[k])});
    with_second += c.site2[k] != kNoIndex;
    if (c.dist2[k] - c.dist1[k] > 2 * tolerance) {
      EXPECT_EQ(g.site1[k], c.site1[k]) << k;
    } else {
      ++near_ties;
    }
  }
  EXPECT_LE(max_difference, tolerance);
  EXPECT_GT(with_second, 0);
  std::cout << in.tri_site.size() << " triangles, " << in.voxels.size()
            << " sample voxels (grid 128^3, band ~3 cells), " << with_second
            << " with a 2nd site within the band, " << near_ties << " near ties\n"
            << "  GPU (" << gpu.device() << "): upload " << g.upload_ms << " ms, compute "
            << g.compute_ms << " ms, readback " << g.readback_ms << " ms\n"
            << "  CPU (2 threads): " << c.compute_ms << " ms\n"
            << "  max |GPU - CPU| = " << max_difference << " (tolerance " << tolerance << ")\n";
  RecordProperty("gpu_compute_ms", std::to_string(g.compute_ms));
  RecordProperty("cpu_compute_ms", std::to_string(c.compute_ms));
}

}  // namespace
}  // namespace vproxq::gl
