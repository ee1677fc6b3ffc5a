#include "core/voronoi/stage2.hpp"

#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "core/voronoi/bins.hpp"
#include "core/voronoi/grid_setup.hpp"
#include "core/voronoi/radix_sort.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <optional>
#include <stdexcept>
#include <utility>

namespace vproxq {
namespace {

// Voxelization and its slack: StageGrid (grid_setup.hpp), shared with the self Stage II.
// The backends' triangle bins are twice the band's cap wide (4 voxels on the default grid),
// or as wide as the cap where the frame's median triangle box (longest side) is at most this
// many caps: see the bins' comment in compute_voronoi_bounds().
constexpr double kSmallTriangleCaps = 0.625;
// Stage II's sampling filter asks each nearby object's triangle hierarchy while an object has
// at most this many nearby objects, else the owner grid.
constexpr std::size_t kFewNearObjects = 8;
// The sampling filter remembers its per-voxel decisions over an object's range of cells up to
// this many cells (a byte each).
constexpr std::int64_t kMaxMemoCells = std::int64_t{1} << 22;

struct VoxelHit {
  std::int64_t voxel;
  Index object;
  Index triangle;
};

/// Which objects' triangle boxes overlap each cell of a coarse grid over the scene (cells of
/// two voxels, coarser where there would be more than kMaxCells): none, one (its id) or
/// several. other_within() answers "may an object other than i have a triangle box within r
/// of this box?" conservatively: a triangle box that comes within r of the box overlaps the
/// box widened by r, hence a cell that the widened box overlaps (both cell ranges come from
/// the same monotone rounding of coordinates).
class OwnerGrid {
 public:
  static constexpr std::int32_t kEmpty = -1, kSeveral = -2;
  static constexpr std::int64_t kMaxCells = std::int64_t{1} << 22;

  OwnerGrid(const VoronoiGrid& grid, const FrameBoxes& boxes) : origin_(grid.origin) {
    std::int32_t k = 2;
    auto cells = [&](std::int32_t per) {
      std::int64_t c = 1;
      for (size_t a = 0; a < 3; ++a) c *= (grid.dims[a] + per - 1) / per;
      return c;
    };
    while (cells(k) > kMaxCells) k *= 2;
    width_ = grid.cell * k;
    for (size_t a = 0; a < 3; ++a) dims_[a] = (grid.dims[a] + k - 1) / k;
    owner_.assign(static_cast<size_t>(cells(k)), kEmpty);
    for (size_t i = 0; i < boxes.triangles.size(); ++i) {
      const auto id = static_cast<std::int32_t>(i);
      for (const AABB& b : boxes.triangles[i]) {
        const auto [lo, hi] = cell_range(b);
        for (std::int32_t z = lo[2]; z <= hi[2]; ++z)
          for (std::int32_t y = lo[1]; y <= hi[1]; ++y)
            for (std::int32_t x = lo[0]; x <= hi[0]; ++x) {
              std::int32_t& o = owner_[cell_id(x, y, z)];
              o = o == kEmpty || o == id ? id : kSeveral;
            }
      }
    }
  }

  bool other_within(const AABB& box, double r, Index i) const {
    AABB wide = box;
    wide.lo.array() -= r;
    wide.hi.array() += r;
    const auto [lo, hi] = cell_range(wide);
    for (std::int32_t z = lo[2]; z <= hi[2]; ++z)
      for (std::int32_t y = lo[1]; y <= hi[1]; ++y)
        for (std::int32_t x = lo[0]; x <= hi[0]; ++x) {
          const std::int32_t o = owner_[cell_id(x, y, z)];
          if (o != kEmpty && o != static_cast<std::int32_t>(i)) return true;
        }
    return false;
  }

 private:
  using Cell = std::array<std::int32_t, 3>;
  std::pair<Cell, Cell> cell_range(const AABB& box) const {
    Cell lo{}, hi{};
    for (size_t a = 0; a < 3; ++a) {
      auto cell_of = [&](double x) {
        const double c = std::floor((x - origin_[static_cast<int>(a)]) / width_);
        return static_cast<std::int32_t>(std::clamp(c, 0.0, static_cast<double>(dims_[a] - 1)));
      };
      lo[a] = cell_of(box.lo[static_cast<int>(a)]);
      hi[a] = cell_of(box.hi[static_cast<int>(a)]);
    }
    return {lo, hi};
  }
  size_t cell_id(std::int32_t x, std::int32_t y, std::int32_t z) const {
    return static_cast<size_t>(x + std::int64_t{dims_[0]} * (y + std::int64_t{dims_[1]} * z));
  }

  Vec3 origin_;
  double width_ = 1;
  Cell dims_{1, 1, 1};
  std::vector<std::int32_t> owner_;
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
  const int default_res = default_grid_resolution(total_tris);
  const int res = grid_resolution > 0 ? grid_resolution : default_res;
  const StageGrid sg = StageGrid::over(scene, res);
  VoronoiGrid& grid = out.grid;
  grid = sg.grid;
  out.delta_precision = sg.delta_precision(backend);
  out.delta = sg.delta(out.delta_precision);
  const double slack = rounding_slack(boxes.magnitude);

  // Bands: object i needs exact values up to U_i + δ (+ slack) so that its capped triangles
  // are culled (D_l = band - δ > D_u); capped at kMaxInterBandCells cells of this grid or of
  // the default one, the larger: finer grids keep the default grid's band in scene units.
  std::vector<double> band_len(n);
  out.band_cap = kMaxInterBandCells * std::max(grid.cell, StageGrid::over(scene, default_res).grid.cell);
  for (size_t i = 0; i < n; ++i)
    band_len[i] = std::min(stage1.upper_bound[i] + out.delta + slack, out.band_cap);
  // The sampling filter's tests below reach a little past the band, so that rounding cannot
  // skip what lies within it: a voxel centre (origin + cell * (index + 1/2)) is within
  // 2^-52 (M + E) of its exact value per coordinate (M: largest coordinate magnitude, E: grid
  // extent), a widened box's corner within 2^-53 (M + reach), and a computed squared box
  // distance within a relative 2^-50 of its exact value; so whatever a test leaves out lies
  // farther than the band. (The frame's rounding slack, ~4.5e5 ulps of M, would do too, but
  // far from the origin it spans the whole grid: 18 grains at 1e12 took 52 s of Stage II at
  // --grid 512 with it.)
  auto reach_of = [&](double len) { return len * (1 + 0x1p-48) + 0x1p-49 * (boxes.magnitude + sg.extent); };
  std::vector<double> reach(n);
  for (size_t i = 0; i < n; ++i) reach[i] = reach_of(band_len[i]);
  // Which triangles are sampled: those within near_len of another object's triangle box, where
  // near_len = U_i + 2 * slack (or the band, when that is shorter). A triangle farther than
  // that from every other object is never part of a pair Stage III tests (its bound is at most
  // D_u + slack <= U_i + slack), so it gets D_l = near_len, which culls it, without a sample;
  // and no sample of it could lower D_u (a voxel whose SD~ + δ is below U_i touches a triangle
  // within U_i of another object).
  std::vector<double> near_len(n), near_reach(n);
  for (size_t i = 0; i < n; ++i) {
    near_len[i] = std::min(stage1.upper_bound[i] + 2 * slack, band_len[i]);
    near_reach[i] = reach_of(near_len[i]);
  }

  // A sample point farther than its band from every other object gets the band back: the
  // backend's walk there finds nothing. So only where another object's triangle boxes come
  // within the band is anything sampled. A triangle whose box is farther than the band from
  // every other object's triangle boxes is not sampled and gets D_l = band (it is at least that
  // far from every other object: more than the band - δ its samples could give). Of a sampled
  // triangle's voxels, those whose centres lie farther than the band from every other object's
  // triangle boxes count as the band without being computed: Lemma 2 still holds, since the
  // point p of the triangle nearest to another object lies in a voxel whose centre c is within
  // sqrt(3) * half of it, and if that voxel counted as the band, every other triangle g has
  // d(p, g) >= d(c, box(g)) - sqrt(3) * half > band - δ. `near`: per object, the objects whose
  // boxes lie within its reach of its box.
  std::vector<std::vector<Index>> near(n);
  {
    const ObjectBoxTree& tree = boxes.object_tree();
    parallel_for(n, threads, [&](size_t i) {
      if (boxes.objects[i].empty()) return;
      const double r = reach[i];
      tree.bvh.query(boxes.objects[i], [r] { return r; }, [&](Index t, double) {
        const Index j = tree.ids[static_cast<size_t>(t)];
        if (j != static_cast<Index>(i)) near[i].push_back(j);
      });
    });
  }
  // Built only where some object will read it (see below).
  std::optional<OwnerGrid> owner_grid;
  if (std::any_of(near.begin(), near.end(), [](const auto& v) { return v.size() > kFewNearObjects; }))
    owner_grid.emplace(grid, boxes);
  const OwnerGrid* owners = owner_grid ? &*owner_grid : nullptr;

  // Conservative voxelization, per object in parallel, then merged in object order.
  std::vector<std::vector<VoxelHit>> hits(n);
  // Per object, the sampled triangles some of whose voxels were left out.
  std::vector<std::vector<std::uint8_t>> capped(n);
  std::vector<std::uint64_t> sampled(n, 0);
  parallel_for(n, threads, [&](size_t i) {
    const Object& o = frame.objects[i];
    auto& lower = out.triangle_lower[i];
    capped[i].assign(lower.size(), 0);
    if (o.num_triangles() == 0) return;
    // Whether object j has a triangle box within d of `box`.
    auto within = [&](const AABB& box, size_t j, double d) {
      return box_distance_squared(box, boxes.objects[j]) <= d * d && boxes.bvh(j).any_within(box, d);
    };
    // Near few objects, through their triangle hierarchies; near many (a container, a floor),
    // through the owner grid, whose cells are coarser but cost the same whatever the count.
    const bool crowded = near[i].size() > kFewNearObjects;
    // Whether another object's triangle box lies within reach of `box`.
    auto other_within = [&](const AABB& box, double r) {
      return crowded ? owners->other_within(box, r, static_cast<Index>(i))
                     : std::any_of(near[i].begin(), near[i].end(), [&](Index j) { return within(box, static_cast<size_t>(j), r); });
    };
    // An object whose Stage I bound is 0 is proven to touch another: no sample can lower its
    // D_u, and with a band of δ (+ slack) a sample culls one of its triangles only where nothing
    // lies within δ of the voxel centre, which saves few exact tests (Stage III then looks only
    // at touching boxes). So its triangles near another object are not sampled and stay
    // uncullable (D_l = -inf); the others get near_len as above. See docs/algorithms.md, "Stage II".
    const bool touching = stage1.upper_bound[i] == 0;
    // Whether a voxel's centre lies within reach of another object's triangle box, against all
    // of near[i]: the answer does not depend on the triangle, so it is found once per voxel
    // (neighbouring triangles share most of their voxels) and remembered over the object's
    // range of cells (when that is not huge).
    // (Named, not a structured binding: C++17 lets no lambda capture one, and clang holds to that.)
    const auto cell_range = sg.cell_range(boxes.objects[i]);
    const StageGrid::Cell& clo = cell_range.first;
    const StageGrid::Cell& chi = cell_range.second;
    std::array<std::int64_t, 3> span{};
    for (size_t a = 0; a < 3; ++a) span[a] = std::int64_t{chi[a]} - clo[a] + 1;
    const std::int64_t cells = span[0] * span[1] * span[2];
    thread_local std::vector<std::uint8_t> memo;  // 0: not decided, 1: keep, 2: leave out
    memo.assign(!touching && cells <= kMaxMemoCells ? static_cast<size_t>(cells) : 0, 0);
    auto keep_voxel = [&](const StageGrid::Cell& c, std::int64_t id) {
      std::uint8_t* m = nullptr;
      if (!memo.empty()) {
        m = &memo[static_cast<size_t>((c[0] - clo[0]) + span[0] * ((c[1] - clo[1]) + span[1] * std::int64_t{c[2] - clo[2]}))];
        if (*m) return *m == 1;
      }
      AABB centre;
      centre.lo = centre.hi = grid.center(id);
      const bool keep = other_within(centre, reach[i]);
      if (m) *m = keep ? 1 : 2;
      return keep;
    };
    for (Index t = 0; t < o.num_triangles(); ++t) {
      const AABB& bt = boxes.triangles[i][static_cast<size_t>(t)];
      if (!other_within(bt, near_reach[i])) {
        lower[static_cast<size_t>(t)] = near_len[i];
        continue;
      }
      if (touching) continue;
      ++sampled[i];
      sg.voxelize_cells(o.triangle(t), bt, [&](const StageGrid::Cell& c, std::int64_t id) {
        if (keep_voxel(c, id))
          hits[i].push_back({id, static_cast<Index>(i), t});
        else
          capped[i][static_cast<size_t>(t)] = 1;
      });
    }
  });
  for (size_t i = 0; i < n; ++i) out.sampled_triangles += sampled[i];

  // Each band is passed to the backend as a float in its units, rounded up.
  std::vector<float> obj_band(n, 0.0f);
  for (size_t i = 0; i < n; ++i) obj_band[i] = sg.backend_band(band_len[i]);

  DvdInput in;
  in.grid = sg.backend_grid();
  struct VoxelBand {
    std::int64_t voxel;
    float band;
    std::int32_t object;
    std::uint32_t hit;  ///< position among all objects' hits (object order)
  };
  std::vector<VoxelBand> vb;
  std::vector<size_t> hit_base(n + 1, 0);
  for (size_t i = 0; i < n; ++i) hit_base[i + 1] = hit_base[i] + hits[i].size();
  if (hit_base[n] >= (std::uint64_t{1} << 32))
    throw std::length_error("Stage II: more than 2^32 voxel marks; use a coarser --grid");
  vb.reserve(hit_base[n]);
  for (size_t i = 0; i < n; ++i)
    for (size_t j = 0; j < hits[i].size(); ++j)
      vb.push_back({hits[i][j].voxel, obj_band[i], static_cast<std::int32_t>(i), static_cast<std::uint32_t>(hit_base[i] + j)});
  stable_radix_sort(vb, [](const VoxelBand& x) { return static_cast<std::uint64_t>(x.voxel); });
  // The sample each hit was merged into, for the scan.
  std::vector<std::uint32_t> hit_sample(hit_base[n]);
  for (size_t k = 0; k < vb.size();) {
    size_t e = k;
    float band = 0;
    bool one_site = true;
    for (; e < vb.size() && vb[e].voxel == vb[k].voxel; ++e) {
      band = std::max(band, vb[e].band);
      one_site = one_site && vb[e].object == vb[k].object;
      hit_sample[vb[e].hit] = static_cast<std::uint32_t>(in.voxels.size());
    }
    in.voxels.push_back(vb[k].voxel);
    in.band.push_back(band);
    // A voxel touched by one object only: the scan below reads the nearest site other than
    // that object, which the backend finds faster without the object's own triangles.
    in.exclude_site.push_back(one_site ? vb[k].object : kNoIndex);
    k = e;
  }
  out.sample_voxels = in.voxels.size();

  // Triangles relative to the origin, in backend units, in object order: only those some
  // sample's walk can reach (reachable_triangles()). Most triangles of a frame are far from
  // every sample, and preparing them cost more than the samples did.
  // A sample's walk reaches its band (at most band_cap) around its voxel, so with bins of
  // 2 band_cap it spans 2 or 3 bins per axis on every grid. Bins of 4 voxels on a grid finer
  // than the default one made the walk cross more bins the finer the grid (skirt at
  // --grid 512: 11 voxels of band, up to 7 bins per axis), each triangle listed in more of
  // them: there the CPU walk took 706 ms per frame instead of 131 (frames 10-12). On the
  // default grid and coarser ones, band_cap is 2 cells (band_cap / cell is exactly 2:
  // in.grid.cell is sg.grid.cell divided by a power of two).
  // Where the triangles are small next to the band (median box side at most
  // kSmallTriangleCaps caps: 1.25 voxels on the default grid), bins as wide as the cap hold
  // fewer triangles each, and few triangles are listed in several: inter-object backend ms per
  // frame with bins of 2 / 4 voxels (default grid; cpu, gpu on llvmpipe): funnel (median
  // 0.83 voxels) 23.2 / 27.3 and 88.8 / 159.6, cloth-ball (0.93) 3.0 / 4.0 and 10.9 / 13.9,
  // breaking (1.04) 1.5 / 1.9 and 5.5 / 7.1, bowl (1.10) 2.5 / 2.7 and 10.5 / 12.0; but
  // skirt (1.51) 8.6 / 5.0 and 34.8 / 19.0, blobs-200 (2.79) 4.4 / 4.5 and 20.0 / 12.6.
  const double cap_cells = out.band_cap / (sg.unit * in.grid.cell);
  const bool small_triangles =
      median_triangle_side(boxes, [](size_t) { return true; }) <= kSmallTriangleCaps * out.band_cap;
  const auto bin_side = std::max<std::int32_t>(1, static_cast<std::int32_t>(std::lround((small_triangles ? 1 : 2) * cap_cells)));
  set_bin_layout(in, bin_size_for(in.grid, bin_side));
  const std::vector<std::vector<Index>> kept = reachable_triangles(
      in, sg, boxes, threads, [](size_t) { return true; }, [](size_t, Index) { return false; });
  fill_dvd_triangles(in, frame, sg, kept);
  out.backend_triangles = in.tri_site.size();
  bin_triangles(in, in.bin_size);
  out.setup_ms = sw.elapsed_ms();

  const DvdOutput dvd = backend.compute(in);
  out.upload_ms = dvd.upload_ms;
  out.compute_ms = dvd.compute_ms;
  out.readback_ms = dvd.readback_ms;

  // Scan: SD~ per triangle and object from the values at their sample voxels (back in scene
  // units: multiplying by the power of two sg.unit is exact).
  sw.restart();
  parallel_for(n, threads, [&](size_t i) {
    double sd_obj_usable = kInfinity;  // min over values below their band
    auto& lower = out.triangle_lower[i];
    std::vector<double> sd_tri(lower.size(), kInfinity);
    for (size_t j = 0; j < hits[i].size(); ++j) {
      const auto& h = hits[i][j];
      const size_t k = hit_sample[hit_base[i] + j];
      const bool first_is_self = dvd.site1[k] == static_cast<std::int32_t>(i);
      const std::int32_t site = first_is_self ? dvd.site2[k] : dvd.site1[k];
      const double v = sg.unit * (first_is_self ? dvd.dist2[k] : dvd.dist1[k]);
      const double band = sg.unit * in.band[k];
      // For D_l: a value at or past the band only says "at least band".
      const double for_lower = site == kNoIndex ? band : std::min(v, band);
      double& st = sd_tri[static_cast<size_t>(h.triangle)];
      st = std::min(st, for_lower);
      if (site != kNoIndex && v < band) sd_obj_usable = std::min(sd_obj_usable, v);
    }
    for (size_t t = 0; t < lower.size(); ++t) {
      if (lower[t] != -kInfinity) continue;  // not sampled: D_l is its band already
      // A voxel left out lies farther than the band from every other object.
      if (capped[i][t]) sd_tri[t] = std::min(sd_tri[t], band_len[i]);
      // Every sampled triangle marks at least one voxel; should one not, it stays uncullable.
      lower[t] = sd_tri[t] == kInfinity ? -kInfinity : sd_tri[t] - out.delta;
    }
    out.object_upper[i] = std::min(stage1.upper_bound[i], sd_obj_usable + out.delta);
  });
  out.scan_ms = sw.elapsed_ms();
  return out;
}

}  // namespace vproxq
