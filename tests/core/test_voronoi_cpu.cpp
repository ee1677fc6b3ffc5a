// Stage II CPU backend and triangle binning against brute-force twins.
//
// The twin of the backend evaluates every triangle at every sample voxel (no bins, no
// prefilter), takes each site's minimum distance below the band, and sorts the sites by
// (distance, site id). It uses the same exact point–triangle distance
// (core/geometry/point_triangle, itself tested against its own twin), so the comparison is
// exact: what is tested is the binning, the bin search, the visit-once rule, the bounding-box
// prefilter and the streaming top-2 update, none of which may change a single bit.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <iostream>
#include <limits>
#include <map>
#include <random>
#include <set>
#include <stdexcept>
#include <vector>

#include "core/geometry/point_triangle.hpp"
#include "core/voronoi/bins.hpp"
#include "core/voronoi/discrete_voronoi.hpp"
#include "support/dvd_input.hpp"

namespace vproxq {
namespace {

using test::sample_point;
using test::triangle_of;

void add_triangle(DvdInput& in, const Triangle& t, std::int32_t site) {
  for (const Vec3& c : t) {
    for (int k = 0; k < 3; ++k) {
      in.tri_xyz_d.push_back(c[k]);
      in.tri_xyz.push_back(static_cast<float>(c[k]));
    }
  }
  in.tri_site.push_back(site);
}

struct SceneOptions {
  int sites = 12;
  int triangles = 400;
  int voxels = 2500;
  double max_band_cells = 6;
  std::int32_t bin_size = 4;
  bool unbounded_bands = true;  ///< some bands 0, +infinity and 1e30
};

/// A random scene: triangles of several sites clustered around random centres inside the
/// grid (relative coordinates), with the awkward cases mixed in: degenerate triangles
/// (collinear corners, repeated corners, a point), exact duplicates in another site (ties),
/// and large triangles spanning many bins. Voxels: a random sorted subset; bands: random,
/// plus 0 and +infinity.
DvdInput random_scene(unsigned seed, const SceneOptions& options) {
  std::mt19937 rng(seed);
  DvdInput in;
  in.grid.origin = Vec3(-1234.5, 1e4, 3.25);  // irrelevant to the backend: all is relative
  in.grid.cell = 0.37;
  in.grid.dims = {40, 33, 27};
  const Vec3 size = in.grid.cell * Vec3(40, 33, 27);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  auto inside = [&](const Vec3& p) -> Vec3 { return p.cwiseMax(Vec3::Zero()).cwiseMin(size); };
  std::vector<Vec3> centres;
  for (int s = 0; s < options.sites; ++s) {
    centres.push_back(Vec3{unit(rng), unit(rng), unit(rng)}.cwiseProduct(size));
  }
  std::uniform_int_distribution<int> pick_site(0, options.sites - 1);
  auto jitter = [&](double scale) -> Vec3 {
    return scale * Vec3{unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5};
  };
  for (int i = 0; i < options.triangles; ++i) {
    const int site = pick_site(rng);
    const Vec3 a = inside(centres[static_cast<std::size_t>(site)] + jitter(8.0));
    Triangle t{a, inside(a + jitter(1.5)), inside(a + jitter(1.5))};
    switch (i % 23) {
      case 3:  // collinear along an axis: exactly degenerate
        t[1] = inside(a + Vec3(0.75, 0, 0));
        t[2] = inside(a + Vec3(0.25, 0, 0));
        break;
      case 7:  // two equal corners
        t[2] = t[0];
        break;
      case 11:  // a point
        t[1] = t[2] = t[0];
        break;
      case 13:  // a large triangle spanning many bins
        t[1] = inside(a + jitter(12.0));
        t[2] = inside(a + jitter(12.0));
        break;
      default:
        break;
    }
    add_triangle(in, t, site);
    if (i % 17 == 5) {  // an exact duplicate in another site: ties go to the smaller id
      add_triangle(in, t, (site + 1 + pick_site(rng)) % options.sites);
    }
  }
  std::set<std::int64_t> ids;
  std::uniform_int_distribution<std::int64_t> pick_voxel(0, in.grid.voxel_count() - 1);
  while (static_cast<int>(ids.size()) < options.voxels) ids.insert(pick_voxel(rng));
  in.voxels.assign(ids.begin(), ids.end());
  for (std::size_t k = 0; k < in.voxels.size(); ++k) {
    float band = static_cast<float>(unit(rng) * options.max_band_cells * in.grid.cell);
    if (options.unbounded_bands) {
      if (k % 101 == 0) band = 0.0f;
      if (k % 103 == 1) band = std::numeric_limits<float>::infinity();
      if (k % 107 == 2) band = 1e30f;
    }
    in.band.push_back(band);
    // Every third voxel ignores one site (as Stage II does for a voxel of a single object).
    in.exclude_site.push_back(k % 3 == 0 ? pick_site(rng) : kNoIndex);
  }
  bin_triangles(in, options.bin_size);
  return in;
}

/// The twin: all triangles, per-site minimum below the band, sites sorted by (distance, id).
DvdOutput brute_force(const DvdInput& in) {
  DvdOutput out;
  std::int32_t site_count = 0;
  for (const std::int32_t s : in.tri_site) site_count = std::max(site_count, s + 1);
  for (std::size_t k = 0; k < in.voxels.size(); ++k) {
    const Vec3 q = sample_point(in.grid, in.voxels[k]);
    const double band = in.band[k];
    std::vector<double> best(static_cast<std::size_t>(site_count), kInfinity);
    const std::int32_t skip = in.exclude_site.empty() ? kNoIndex : in.exclude_site[k];
    for (std::size_t t = 0; t < in.tri_site.size(); ++t) {
      if (in.tri_site[t] == skip) continue;
      const double d = std::sqrt(point_triangle_distance(q, triangle_of(in, t)).squared_distance);
      double& b = best[static_cast<std::size_t>(in.tri_site[t])];
      if (d < band) b = std::min(b, d);
    }
    std::vector<std::pair<double, std::int32_t>> order;
    for (std::int32_t s = 0; s < site_count; ++s) {
      if (best[static_cast<std::size_t>(s)] < kInfinity)
        order.emplace_back(best[static_cast<std::size_t>(s)], s);
    }
    std::sort(order.begin(), order.end());
    out.site1.push_back(order.size() > 0 ? order[0].second : kNoIndex);
    const bool has2 = order.size() > 1 && skip == kNoIndex;  // only the nearest with a skip
    out.site2.push_back(has2 ? order[1].second : kNoIndex);
    out.dist1.push_back(order.size() > 0 ? static_cast<float>(order[0].first) : in.band[k]);
    out.dist2.push_back(has2 ? static_cast<float>(order[1].first) : in.band[k]);
  }
  return out;
}

void expect_same(const DvdInput& in, const DvdOutput& got, const DvdOutput& expected) {
  ASSERT_EQ(got.site1.size(), in.voxels.size());
  ASSERT_EQ(got.site2.size(), in.voxels.size());
  ASSERT_EQ(got.dist1.size(), in.voxels.size());
  ASSERT_EQ(got.dist2.size(), in.voxels.size());
  int failures = 0;
  // Equal, or within 1e-12 (an infinite band is reported as is).
  auto close = [](float a, float b) { return a == b || std::abs(double{a} - double{b}) <= 1e-12; };
  for (std::size_t k = 0; k < in.voxels.size() && failures < 10; ++k) {
    const bool same = got.site1[k] == expected.site1[k] && got.site2[k] == expected.site2[k] &&
                      close(got.dist1[k], expected.dist1[k]) && close(got.dist2[k], expected.dist2[k]);
    if (!same) {
      ++failures;
      ADD_FAILURE() << "voxel " << in.voxels[k] << " (band " << in.band[k] << "): got sites "
                    << got.site1[k] << ", " << got.site2[k] << " at " << got.dist1[k] << ", "
                    << got.dist2[k] << "; brute force " << expected.site1[k] << ", "
                    << expected.site2[k] << " at " << expected.dist1[k] << ", "
                    << expected.dist2[k];
    }
  }
}

TEST(VoronoiCpu, MatchesBruteForceOnRandomScenes) {
  for (unsigned seed : {1u, 2u, 3u}) {
    const DvdInput in = random_scene(seed, {});
    const DvdOutput expected = brute_force(in);
    for (int threads : {1, 3}) {
      SCOPED_TRACE(testing::Message() << "seed " << seed << ", threads " << threads);
      const auto backend = make_cpu_voronoi_backend(threads);
      const DvdOutput got = backend->compute(in);
      expect_same(in, got, expected);
      EXPECT_GE(got.compute_ms, 0.0);
      EXPECT_EQ(got.upload_ms, 0.0);
      EXPECT_EQ(got.readback_ms, 0.0);
    }
    // Sanity of the scene: both slots are exercised, and so is "none within the band".
    int with_two = 0, with_none = 0;
    for (std::size_t k = 0; k < in.voxels.size(); ++k) {
      with_two += expected.site2[k] != kNoIndex;
      with_none += expected.site1[k] == kNoIndex;
    }
    EXPECT_GT(with_two, 100);
    EXPECT_GT(with_none, 10);
  }
}

TEST(VoronoiCpu, ResultDoesNotDependOnBinSize) {
  for (std::int32_t bin_size : {1, 3, 7, 64}) {
    SceneOptions options;
    options.bin_size = bin_size;
    options.voxels = 800;
    const DvdInput in = random_scene(11, options);
    SCOPED_TRACE(testing::Message() << "bin size " << bin_size);
    expect_same(in, make_cpu_voronoi_backend(2)->compute(in), brute_force(in));
  }
}

// Stage II leaves out of the backend's input the triangles whose boxes overlap no bin that a
// sample's walk visits (reached_bins()): the output must be the twin's on all triangles.
TEST(VoronoiCpu, TrianglesNoSampleReachesCanBeLeftOut) {
  for (unsigned seed : {4u, 5u, 6u}) {
    SceneOptions options;
    options.voxels = 60;
    options.max_band_cells = 3;  // Stage II's cap
    options.unbounded_bands = false;
    const DvdInput in = random_scene(seed, options);
    const DvdOutput expected = brute_force(in);
    DvdInput part = in;
    part.tri_xyz.clear();
    part.tri_xyz_d.clear();
    part.tri_site.clear();
    const std::vector<std::uint8_t> reached = reached_bins(in);
    for (std::size_t t = 0; t < in.tri_site.size(); ++t) {
      const Triangle tri = triangle_of(in, t);
      const Vec3 lo = tri[0].cwiseMin(tri[1]).cwiseMin(tri[2]), hi = tri[0].cwiseMax(tri[1]).cwiseMax(tri[2]);
      if (reaches(in, reached, bins_overlapping(in, lo, hi))) add_triangle(part, tri, in.tri_site[t]);
    }
    bin_triangles(part, options.bin_size);
    SCOPED_TRACE(testing::Message() << "seed " << seed << ": " << part.tri_site.size() << " of "
                                    << in.tri_site.size() << " triangles kept");
    // Many triangles are left out, and the samples still see sites within their bands.
    EXPECT_LT(4 * part.tri_site.size(), 3 * in.tri_site.size());
    int found = 0;
    for (std::size_t k = 0; k < in.voxels.size(); ++k) found += expected.site1[k] != kNoIndex;
    EXPECT_GT(found, 10) << "of " << in.voxels.size();
    expect_same(part, make_cpu_voronoi_backend(2)->compute(part), expected);
  }
}

TEST(VoronoiCpu, TiesGoToTheSmallerSiteId) {
  DvdInput in;
  in.grid.cell = 1.0;
  in.grid.dims = {8, 8, 8};
  const Triangle t{Vec3(1, 1, 1), Vec3(3, 1, 1), Vec3(1, 3, 1)};
  add_triangle(in, t, 5);
  add_triangle(in, t, 2);
  add_triangle(in, t, 9);
  // Site 7 is farther (z = 4): never among the two nearest where the others are in range.
  add_triangle(in, {Vec3(1, 1, 4), Vec3(3, 1, 4), Vec3(1, 3, 4)}, 7);
  in.voxels = {0, 1 + 8 * (1 + 8 * 1), 2 + 8 * (0 + 8 * 1)};
  in.band = {100.0f, 100.0f, 100.0f};
  bin_triangles(in, 2);
  const DvdOutput out = make_cpu_voronoi_backend(1)->compute(in);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(out.site1[k], 2) << k;
    EXPECT_EQ(out.site2[k], 5) << k;
    EXPECT_EQ(out.dist1[k], out.dist2[k]) << k;
  }
  EXPECT_FLOAT_EQ(out.dist1[1], 0.5f);  // centre (1.5, 1.5, 1.5), plane z = 1
  expect_same(in, out, brute_force(in));
}

TEST(VoronoiCpu, NoSitesOrNoVoxels) {
  DvdInput in;
  in.grid.dims = {4, 4, 4};
  in.voxels = {0, 5, 63};
  in.band = {1.0f, 0.0f, std::numeric_limits<float>::infinity()};
  bin_triangles(in, 4);
  const DvdOutput out = make_cpu_voronoi_backend(2)->compute(in);
  for (std::size_t k = 0; k < 3; ++k) {
    EXPECT_EQ(out.site1[k], kNoIndex);
    EXPECT_EQ(out.site2[k], kNoIndex);
    EXPECT_EQ(out.dist1[k], in.band[k]);
    EXPECT_EQ(out.dist2[k], in.band[k]);
  }
  in.voxels.clear();
  in.band.clear();
  EXPECT_TRUE(make_cpu_voronoi_backend(2)->compute(in).site1.empty());
}

TEST(VoronoiCpu, RejectsInconsistentInput) {
  SceneOptions options;
  options.sites = 3;
  options.triangles = 20;
  options.voxels = 10;
  DvdInput in = random_scene(5, options);
  const auto backend = make_cpu_voronoi_backend(1);
  DvdInput bad = in;
  bad.band.pop_back();
  EXPECT_THROW(backend->compute(bad), std::invalid_argument);
  bad = in;
  bad.voxels.back() = in.grid.voxel_count();
  EXPECT_THROW(backend->compute(bad), std::invalid_argument);
  bad = in;
  bad.band[0] = std::numeric_limits<float>::quiet_NaN();
  EXPECT_THROW(backend->compute(bad), std::invalid_argument);
  bad = in;
  bad.bin_offsets.pop_back();
  EXPECT_THROW(backend->compute(bad), std::invalid_argument);
  EXPECT_THROW(bin_triangles(in, 0), std::invalid_argument);
}

TEST(VoronoiCpu, NameDeviceAndErrorBound) {
  const auto backend = make_cpu_voronoi_backend(1);
  EXPECT_EQ(backend->name(), "cpu");
  EXPECT_EQ(backend->device(), "");
  // Dominated by rounding the double distance to float32 (see cpu_backend.cpp).
  const double extent = 100.0;
  const double bound = backend->distance_error_bound(extent);
  EXPECT_GE(bound, 2.0 * std::sqrt(3.0) * extent * 0x1p-24);
  EXPECT_LE(bound, 1e-5 * extent);
}

// ---- Bins ----

TEST(VoronoiBins, CsrStructureMatchesBoundingBoxes) {
  for (std::int32_t bin_size : {1, 4, 5}) {
    SceneOptions options;
    options.bin_size = bin_size;
    const DvdInput in = random_scene(21, options);
    SCOPED_TRACE(testing::Message() << "bin size " << bin_size);
    for (std::size_t a = 0; a < 3; ++a) {
      EXPECT_EQ(in.bin_dims[a], (in.grid.dims[a] + bin_size - 1) / bin_size);
    }
    const std::size_t bins =
        static_cast<std::size_t>(in.bin_dims[0]) * in.bin_dims[1] * in.bin_dims[2];
    ASSERT_EQ(in.bin_offsets.size(), bins + 1);
    EXPECT_EQ(in.bin_offsets.front(), 0);
    EXPECT_EQ(static_cast<std::size_t>(in.bin_offsets.back()), in.bin_tris.size());
    // Expected listing, from each triangle's box computed independently.
    std::vector<std::vector<std::int32_t>> expected(bins);
    for (std::size_t t = 0; t < in.tri_site.size(); ++t) {
      const Triangle tri = triangle_of(in, t);
      std::array<std::int32_t, 3> lo{}, hi{};
      for (int k = 0; k < 3; ++k) {
        const auto a = static_cast<std::size_t>(k);
        const double mn = std::min({tri[0][k], tri[1][k], tri[2][k]});
        const double mx = std::max({tri[0][k], tri[1][k], tri[2][k]});
        auto voxel = [&](double x) {
          return std::clamp(static_cast<std::int32_t>(std::floor(x / in.grid.cell)), 0,
                            in.grid.dims[a] - 1);
        };
        lo[a] = voxel(mn) / bin_size;
        hi[a] = voxel(mx) / bin_size;
      }
      for (std::int32_t z = lo[2]; z <= hi[2]; ++z)
        for (std::int32_t y = lo[1]; y <= hi[1]; ++y)
          for (std::int32_t x = lo[0]; x <= hi[0]; ++x)
            expected[static_cast<std::size_t>(bin_id(in, x, y, z))].push_back(
                static_cast<std::int32_t>(t));
    }
    for (std::size_t b = 0; b < bins; ++b) {
      const std::vector<std::int32_t> got(in.bin_tris.begin() + in.bin_offsets[b],
                                          in.bin_tris.begin() + in.bin_offsets[b + 1]);
      ASSERT_EQ(got, expected[b]) << "bin " << b;  // also checks the increasing order
    }
  }
}

TEST(VoronoiBins, EveryTriangleWithinRadiusIsFound) {
  for (std::int32_t bin_size : {1, 4, 6}) {
    SceneOptions options;
    options.bin_size = bin_size;
    const DvdInput in = random_scene(31, options);
    std::mt19937 rng(7);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    const Vec3 size = in.grid.cell * Vec3(in.grid.dims[0], in.grid.dims[1], in.grid.dims[2]);
    std::int64_t checked = 0;
    for (int i = 0; i < 400; ++i) {
      // Points inside and slightly outside the grid, radii from 0 to a third of the grid.
      const Vec3 q = Vec3{unit(rng) * 1.2 - 0.1, unit(rng) * 1.2 - 0.1, unit(rng) * 1.2 - 0.1}
                         .cwiseProduct(size);
      std::vector<double> distances(in.tri_site.size());
      for (std::size_t t = 0; t < distances.size(); ++t) {
        distances[t] = std::sqrt(point_triangle_distance(q, triangle_of(in, t)).squared_distance);
      }
      std::vector<double> radii{0.0, unit(rng) * 4 * in.grid.cell, unit(rng) * size.maxCoeff() / 3};
      // A radius equal to some triangle's distance: the boundary case of the closed ball.
      radii.push_back(distances[static_cast<std::size_t>(i) % distances.size()]);
      for (const double r : radii) {
        const BinRange range = bins_within(in, q, r);
        std::set<std::int32_t> found;
        for (std::int32_t z = range.lo[2]; z <= range.hi[2]; ++z)
          for (std::int32_t y = range.lo[1]; y <= range.hi[1]; ++y)
            for (std::int32_t x = range.lo[0]; x <= range.hi[0]; ++x) {
              const auto b = static_cast<std::size_t>(bin_id(in, x, y, z));
              found.insert(in.bin_tris.begin() + in.bin_offsets[b],
                           in.bin_tris.begin() + in.bin_offsets[b + 1]);
            }
        for (std::size_t t = 0; t < distances.size(); ++t) {
          if (distances[t] <= r) {
            ++checked;
            ASSERT_TRUE(found.count(static_cast<std::int32_t>(t)))
                << "triangle " << t << " at distance " << distances[t] << " <= " << r << " from ("
                << q.transpose() << ") was not found";
          }
        }
      }
    }
    EXPECT_GT(checked, 1000);
  }
}

TEST(VoronoiBins, InfiniteRadiusVisitsEveryBin) {
  const DvdInput in = random_scene(41, {});
  const BinRange range = bins_within(in, Vec3(1, 2, 3), kInfinity);
  for (std::size_t a = 0; a < 3; ++a) {
    EXPECT_EQ(range.lo[a], 0);
    EXPECT_EQ(range.hi[a], in.bin_dims[a] - 1);
  }
}

// reached_bins() marks every bin a sample's walk visits (bins_within() of its centre and band),
// for bands of every size (0, a fraction of a cell, several bins, infinite), with several bin
// sizes; and not every bin where the bands are small.
TEST(VoronoiBins, ReachedBinsHoldEveryBinASampleVisits) {
  for (const std::int32_t bin_size : {1, 3, 4}) {
    SceneOptions options;
    options.voxels = 300;
    options.bin_size = bin_size;
    DvdInput in = random_scene(43, options);
    SCOPED_TRACE(testing::Message() << "bin size " << bin_size);
    int missed = 0;
    for (std::size_t k = 0; k < in.voxels.size(); ++k) {
      // One sample at a time: the others' bins would hide a miss.
      DvdInput one = in;
      one.voxels = {in.voxels[k]};
      one.band = {in.band[k]};
      const std::vector<std::uint8_t> reached = reached_bins(one);
      const BinRange r = bins_within(in, sample_point(in.grid, in.voxels[k]), in.band[k]);
      for (std::int32_t z = r.lo[2]; z <= r.hi[2]; ++z)
        for (std::int32_t y = r.lo[1]; y <= r.hi[1]; ++y)
          for (std::int32_t x = r.lo[0]; x <= r.hi[0]; ++x) missed += !reached[static_cast<std::size_t>(bin_id(in, x, y, z))];
    }
    EXPECT_EQ(missed, 0);
    // With small bands only (a cell at most), part of the grid stays unreached.
    for (float& b : in.band) b = std::min(b, static_cast<float>(in.grid.cell));
    in.voxels.resize(30);
    in.band.resize(30);
    const std::vector<std::uint8_t> few = reached_bins(in);
    EXPECT_LT(std::count(few.begin(), few.end(), 1), static_cast<std::ptrdiff_t>(few.size()) / 2);
  }
}

// bin_size_for(): the preferred side while the bins fit in kMaxBins, else the smallest side
// that fits (so the one below it does not).
TEST(VoronoiBins, BinSizeGrowsOnlyForVeryFineGrids) {
  auto bins = [](const VoronoiGrid& g, std::int64_t side) {
    std::int64_t n = 1;
    for (const std::int32_t d : g.dims) n *= (d + side - 1) / side;
    return n;
  };
  VoronoiGrid g;
  for (const auto& dims : std::vector<std::array<std::int32_t, 3>>{
           {1, 1, 1}, {256, 200, 64}, {1024, 1024, 1024}, {1025, 1024, 1024}, {2048, 1900, 1700},
           {4096, 4096, 4096}, {4096, 3, 2}}) {
    g.dims = dims;
    const std::int32_t side = bin_size_for(g, 4);
    SCOPED_TRACE(testing::Message() << dims[0] << "x" << dims[1] << "x" << dims[2] << ": side " << side);
    EXPECT_GE(side, 4);
    EXPECT_LE(bins(g, side), kMaxBins);
    if (side > 4) {
      EXPECT_GT(bins(g, side - 1), kMaxBins);
    }
  }
  g.dims = {1024, 1024, 1024};
  EXPECT_EQ(bin_size_for(g, 4), 4);
  g.dims = {2048, 2048, 2048};
  EXPECT_EQ(bin_size_for(g, 4), 8);
}

}  // namespace
}  // namespace vproxq
