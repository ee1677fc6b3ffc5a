#include "core/voronoi/stage2.hpp"

#include "core/geometry/triangle_box.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "core/voronoi/bins.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>

namespace vproxq {
namespace {

// Voxelization: the SAT test runs in double on coordinates relative to the grid origin, of
// magnitude <= the grid extent E; its projections are off by at most a few ulps of E. Widening
// the voxel's half side by kVoxelSlackRel * (E + cell) (~4.5e6 ulps) makes the test
// conservative: every voxel that the exact triangle touches is marked. A marked voxel centre
// is then within (cell/2 + slack) * sqrt(3) of the triangle, which δ accounts for.
constexpr double kVoxelSlackRel = 1e-9;
// Bands are capped at this many cells: a narrower band only weakens culling, never
// correctness (values at the cap give D_l = cap - δ, which then simply does not cull).
constexpr double kMaxBandCells = 3.0;
// Bins of this many voxels per side for the backends' triangle lookup.
constexpr std::int32_t kBinSize = 4;

struct VoxelHit {
  std::int64_t voxel;
  Index object;
  Index triangle;
};

}  // namespace

int default_grid_resolution(std::int64_t triangles) {
  const double g = 4.0 * std::cbrt(static_cast<double>(std::max<std::int64_t>(triangles, 1)));
  return static_cast<int>(std::clamp(std::lround(g), 32L, 256L));
}

VoronoiBounds compute_voronoi_bounds(const Frame& frame, const FrameBoxes& boxes,
                                     const ObjectBroadPhase& stage1,
                                     DiscreteVoronoiBackend& backend, int grid_resolution,
                                     int threads) {
  Stopwatch sw;
  VoronoiBounds out;
  const size_t n = frame.objects.size();
  out.object_upper = stage1.upper_bound;
  out.triangle_lower.resize(n);
  std::int64_t total_tris = 0;
  AABB scene;
  for (size_t i = 0; i < n; ++i) {
    out.triangle_lower[i].assign(static_cast<size_t>(frame.objects[i].num_triangles()), -kInfinity);
    total_tris += frame.objects[i].num_triangles();
    if (!boxes.objects[i].empty()) scene.extend(boxes.objects[i]);
  }
  if (scene.empty()) return out;

  // Grid: cubic cells, `res` cells along the longest axis.
  const int res = grid_resolution > 0 ? grid_resolution : default_grid_resolution(total_tris);
  const Vec3 ext = scene.hi - scene.lo;
  const double longest = std::max(ext.maxCoeff(), 1e-300);
  VoronoiGrid& grid = out.grid;
  grid.cell = longest / res;
  grid.origin = scene.lo;
  for (int k = 0; k < 3; ++k)
    grid.dims[k] = std::max<std::int32_t>(1, static_cast<std::int32_t>(std::ceil(ext[k] / grid.cell)));
  const double extent = (grid.cell * Vec3(grid.dims[0], grid.dims[1], grid.dims[2])).norm();
  const double voxel_slack = kVoxelSlackRel * (extent + grid.cell);
  const double half = 0.5 * grid.cell + voxel_slack;
  out.delta_precision = backend.distance_error_bound(extent);
  out.delta = std::sqrt(3.0) * half + out.delta_precision;
  const double slack = rounding_slack(boxes.magnitude);

  // Conservative voxelization, per object in parallel, then merged in object order.
  std::vector<std::vector<VoxelHit>> hits(n);
  parallel_for(n, threads, [&](size_t i) {
    const Object& o = frame.objects[i];
    for (Index t = 0; t < o.num_triangles(); ++t) {
      Triangle tri = o.triangle(t);
      for (auto& p : tri) p -= grid.origin;
      const AABB& tb = boxes.triangles[i][static_cast<size_t>(t)];
      std::array<std::int32_t, 3> lo{}, hi{};
      for (int k = 0; k < 3; ++k) {
        auto cell_of = [&](double x) {
          return std::clamp<std::int32_t>(static_cast<std::int32_t>(std::floor(x / grid.cell)), 0, grid.dims[k] - 1);
        };
        lo[k] = cell_of(tb.lo[k] - grid.origin[k] - voxel_slack);
        hi[k] = cell_of(tb.hi[k] - grid.origin[k] + voxel_slack);
      }
      for (std::int32_t z = lo[2]; z <= hi[2]; ++z)
        for (std::int32_t y = lo[1]; y <= hi[1]; ++y)
          for (std::int32_t x = lo[0]; x <= hi[0]; ++x) {
            const Vec3 c = grid.cell * Vec3(x + 0.5, y + 0.5, z + 0.5);
            if (!triangle_box_overlap(tri, c, half)) continue;
            const std::int64_t id = x + std::int64_t{grid.dims[0]} * (y + std::int64_t{grid.dims[1]} * z);
            hits[i].push_back({id, static_cast<Index>(i), t});
          }
    }
  });

  // Bands: object i needs exact values up to U_i + δ (+ slack) so that its capped triangles
  // are culled (D_l = band - δ > D_u); capped at kMaxBandCells cells.
  std::vector<double> obj_band(n, 0.0);
  for (size_t i = 0; i < n; ++i)
    obj_band[i] = std::min(stage1.upper_bound[i] + out.delta + slack, kMaxBandCells * grid.cell);

  DvdInput in;
  in.grid = grid;
  std::vector<std::pair<std::int64_t, float>> vb;
  size_t total_hits = 0;
  for (const auto& h : hits) total_hits += h.size();
  vb.reserve(total_hits);
  for (size_t i = 0; i < n; ++i)
    for (const auto& h : hits[i]) vb.emplace_back(h.voxel, static_cast<float>(obj_band[i]));
  std::sort(vb.begin(), vb.end(), [](const auto& a, const auto& b) { return a.first < b.first; });
  for (size_t k = 0; k < vb.size();) {
    size_t e = k;
    float band = 0;
    while (e < vb.size() && vb[e].first == vb[k].first) band = std::max(band, vb[e++].second);
    in.voxels.push_back(vb[k].first);
    // Round the float band up so that it is never below the double band.
    in.band.push_back(std::nextafter(band, std::numeric_limits<float>::infinity()));
    k = e;
  }
  out.sample_voxels = in.voxels.size();

  // Triangles relative to the origin, in object order.
  std::vector<std::int64_t> tri_base(n + 1, 0);
  for (size_t i = 0; i < n; ++i) tri_base[i + 1] = tri_base[i] + frame.objects[i].num_triangles();
  in.tri_xyz.resize(static_cast<size_t>(tri_base[n]) * 9);
  in.tri_xyz_d.resize(in.tri_xyz.size());
  in.tri_site.resize(static_cast<size_t>(tri_base[n]));
  for (size_t i = 0; i < n; ++i) {
    const Object& o = frame.objects[i];
    for (Index t = 0; t < o.num_triangles(); ++t) {
      const size_t g = static_cast<size_t>(tri_base[i] + t);
      const Triangle tri = o.triangle(t);
      for (int c = 0; c < 3; ++c)
        for (int k = 0; k < 3; ++k) {
          const double v = tri[static_cast<size_t>(c)][k] - grid.origin[k];
          in.tri_xyz_d[g * 9 + static_cast<size_t>(c * 3 + k)] = v;
          in.tri_xyz[g * 9 + static_cast<size_t>(c * 3 + k)] = static_cast<float>(v);
        }
      in.tri_site[g] = static_cast<std::int32_t>(i);
    }
  }
  bin_triangles(in, kBinSize);
  out.setup_ms = sw.elapsed_ms();

  const DvdOutput dvd = backend.compute(in);
  out.upload_ms = dvd.upload_ms;
  out.compute_ms = dvd.compute_ms;
  out.readback_ms = dvd.readback_ms;

  // Scan: SD~ per triangle and object from the values at their sample voxels.
  sw.restart();
  parallel_for(n, threads, [&](size_t i) {
    double sd_obj_usable = kInfinity;  // min over values below their band
    auto& lower = out.triangle_lower[i];
    std::vector<double> sd_tri(lower.size(), kInfinity);
    for (const auto& h : hits[i]) {
      const size_t k = static_cast<size_t>(
          std::lower_bound(in.voxels.begin(), in.voxels.end(), h.voxel) - in.voxels.begin());
      const bool first_is_self = dvd.site1[k] == static_cast<std::int32_t>(i);
      const std::int32_t site = first_is_self ? dvd.site2[k] : dvd.site1[k];
      const double v = first_is_self ? dvd.dist2[k] : dvd.dist1[k];
      const double band = in.band[k];
      // For D_l: a value at or past the band only says "at least band".
      const double for_lower = site == kNoIndex ? band : std::min(v, band);
      double& st = sd_tri[static_cast<size_t>(h.triangle)];
      st = std::min(st, for_lower);
      if (site != kNoIndex && v < band) sd_obj_usable = std::min(sd_obj_usable, v);
    }
    // Every triangle marks at least one voxel; should one not, it stays uncullable.
    for (size_t t = 0; t < lower.size(); ++t)
      lower[t] = sd_tri[t] == kInfinity ? -kInfinity : sd_tri[t] - out.delta;
    out.object_upper[i] = std::min(stage1.upper_bound[i], sd_obj_usable + out.delta);
  });
  out.scan_ms = sw.elapsed_ms();
  return out;
}

}  // namespace vproxq
