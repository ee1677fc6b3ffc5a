#include "core/voronoi/ccd_stage2.hpp"

#include "core/broad_phase/object_broad_phase.hpp"
#include "core/parallel.hpp"
#include "core/voronoi/stage2.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <cmath>

namespace vproxq {
namespace {

// Voxel regions: voxel (x, y, z) is the cube of half side `half` around its computed centre
// cell * (x + 0.5, ...) (coordinates relative to the grid origin). With half = cell/2 plus
// kVoxelSlackRel * (E + cell) (E: the grid's extent, ~4.5e6 ulps of it) the regions cover
// space despite rounding of the centres, and every rounding of the test below (coordinates
// relative to the origin, dot products of 3 terms: a few ulps of E times |n|_1) is absorbed
// as well, so a voxel is marked whenever its region meets the widened hull.
constexpr double kVoxelSlackRel = 1e-9;
constexpr std::int64_t kChunk = 256;

/// True when an axis n proves the cube (centre c, half side r) disjoint from the hull of
/// `pts` widened by `margin` (Minkowski sum with a cube of half side margin). The hull's
/// projection onto n is the interval spanned by its vertices' projections; the cube's and
/// the margin cube's are c.n ± (r + margin)|n|_1.
bool separated(const std::array<Vec3, 6>& pts, const Vec3& n, const Vec3& c, double r_plus_margin) {
  const double n1 = n.cwiseAbs().sum();
  if (!(n1 > 0)) return false;
  double lo = kInfinity, hi = -kInfinity;
  for (const Vec3& p : pts) {
    const double d = p.dot(n);
    lo = std::min(lo, d);
    hi = std::max(hi, d);
  }
  const double cn = c.dot(n);
  const double reach = r_plus_margin * n1;
  return hi < cn - reach || lo > cn + reach;
}

}  // namespace

CcdVoxelCulling::CcdVoxelCulling(const Frame& from, const Frame& to, const CcdSweep& sweep,
                                 int grid_resolution, int threads) {
  const size_t n = from.objects.size();
  voxel_ids_.assign(n, {});
  offsets_.assign(n, {});
  foreign_.assign(n, {});
  AABB scene;
  std::int64_t total_tris = 0;
  for (Index i : sweep.participants.objects) {
    if (sweep.objects[static_cast<size_t>(i)].empty()) continue;
    scene.extend(sweep.objects[static_cast<size_t>(i)]);
    total_tris += from.objects[static_cast<size_t>(i)].num_triangles();
  }
  if (scene.empty()) return;
  const int res = grid_resolution > 0 ? grid_resolution : default_grid_resolution(total_tris);
  const Vec3 ext = scene.hi - scene.lo;
  const double longest = std::max(ext.maxCoeff(), 1e-300);
  grid_.cell = longest / res;
  grid_.origin = scene.lo;
  for (int k = 0; k < 3; ++k)
    grid_.dims[k] = std::max<std::int32_t>(1, static_cast<std::int32_t>(std::ceil(ext[k] / grid_.cell)));
  const double extent = (grid_.cell * Vec3(grid_.dims[0], grid_.dims[1], grid_.dims[2])).norm();
  const double voxel_slack = kVoxelSlackRel * (extent + grid_.cell);
  const double reach = 0.5 * grid_.cell + voxel_slack + sweep.margin;

  // Work items: chunks of triangles of each participating object.
  struct Item {
    Index object, first, last;
  };
  std::vector<Item> items;
  for (Index i : sweep.participants.objects) {
    const Index nt = from.objects[static_cast<size_t>(i)].num_triangles();
    for (Index t = 0; t < nt; t += static_cast<Index>(kChunk)) items.push_back({i, t, std::min<Index>(nt, t + static_cast<Index>(kChunk))});
  }
  std::vector<std::vector<std::vector<std::int64_t>>> per_tri(n);
  for (Index i : sweep.participants.objects)
    per_tri[static_cast<size_t>(i)].resize(static_cast<size_t>(from.objects[static_cast<size_t>(i)].num_triangles()));
  parallel_for(items.size(), threads, [&](size_t k) {
    const Item& it = items[k];
    const Object& a = from.objects[static_cast<size_t>(it.object)];
    const Object& b = to.objects[static_cast<size_t>(it.object)];
    for (Index t = it.first; t < it.last; ++t) {
      const Face& f = a.topology->faces[static_cast<size_t>(t)];
      std::array<Vec3, 6> pts;
      for (int c = 0; c < 3; ++c) {
        pts[static_cast<size_t>(c)] = a.positions[static_cast<size_t>(f[static_cast<size_t>(c)])] - grid_.origin;
        pts[static_cast<size_t>(c + 3)] = b.positions[static_cast<size_t>(f[static_cast<size_t>(c)])] - grid_.origin;
      }
      // Separating axes tried besides the coordinate axes (the index range below): the
      // triangle's normal at the start, at the end and halfway. Any axis is valid.
      const Vec3 n0 = (pts[1] - pts[0]).cross(pts[2] - pts[0]);
      const Vec3 n1 = (pts[4] - pts[3]).cross(pts[5] - pts[3]);
      const Vec3 m0 = 0.5 * (pts[0] + pts[3]), m1 = 0.5 * (pts[1] + pts[4]), m2 = 0.5 * (pts[2] + pts[5]);
      const Vec3 nm = (m1 - m0).cross(m2 - m0);
      const AABB& tb = sweep.triangles[static_cast<size_t>(it.object)][static_cast<size_t>(t)];
      std::array<std::int32_t, 3> lo{}, hi{};
      for (int d = 0; d < 3; ++d) {
        auto cell_of = [&](double x) {
          return std::clamp<std::int32_t>(static_cast<std::int32_t>(std::floor(x / grid_.cell)), 0, grid_.dims[d] - 1);
        };
        // tb is already widened by the margin.
        lo[d] = cell_of(tb.lo[d] - grid_.origin[d] - voxel_slack);
        hi[d] = cell_of(tb.hi[d] - grid_.origin[d] + voxel_slack);
      }
      auto& out = per_tri[static_cast<size_t>(it.object)][static_cast<size_t>(t)];
      for (std::int32_t z = lo[2]; z <= hi[2]; ++z)
        for (std::int32_t y = lo[1]; y <= hi[1]; ++y)
          for (std::int32_t x = lo[0]; x <= hi[0]; ++x) {
            const Vec3 c = grid_.cell * Vec3(x + 0.5, y + 0.5, z + 0.5);
            if (separated(pts, n0, c, reach) || separated(pts, n1, c, reach) ||
                separated(pts, nm, c, reach))
              continue;
            out.push_back(x + std::int64_t{grid_.dims[0]} * (y + std::int64_t{grid_.dims[1]} * z));
          }
    }
  });

  // CSR per object, and the voxels marked by two or more objects.
  std::vector<std::pair<std::int64_t, Index>> voxel_objects;
  for (Index i : sweep.participants.objects) {
    auto& rows = per_tri[static_cast<size_t>(i)];
    auto& off = offsets_[static_cast<size_t>(i)];
    auto& ids = voxel_ids_[static_cast<size_t>(i)];
    off.assign(rows.size() + 1, 0);
    for (size_t t = 0; t < rows.size(); ++t) {
      ids.insert(ids.end(), rows[t].begin(), rows[t].end());
      off[t + 1] = static_cast<std::int32_t>(ids.size());
    }
    marks_ += ids.size();
    std::vector<std::int64_t> distinct = ids;
    std::sort(distinct.begin(), distinct.end());
    distinct.erase(std::unique(distinct.begin(), distinct.end()), distinct.end());
    for (std::int64_t v : distinct) voxel_objects.emplace_back(v, i);
    rows.clear();
    rows.shrink_to_fit();
  }
  std::sort(voxel_objects.begin(), voxel_objects.end());
  std::vector<std::int64_t> shared;  // voxels with marks of at least two objects, ascending
  for (size_t k = 1; k < voxel_objects.size(); ++k)
    if (voxel_objects[k].first == voxel_objects[k - 1].first &&
        (shared.empty() || shared.back() != voxel_objects[k].first))
      shared.push_back(voxel_objects[k].first);
  for (Index i : sweep.participants.objects) {
    const auto& off = offsets_[static_cast<size_t>(i)];
    const auto& ids = voxel_ids_[static_cast<size_t>(i)];
    auto& fr = foreign_[static_cast<size_t>(i)];
    fr.assign(off.size() - 1, 0);
    for (size_t t = 0; t + 1 < off.size(); ++t)
      for (std::int32_t k = off[t]; k < off[t + 1]; ++k)
        if (std::binary_search(shared.begin(), shared.end(), ids[static_cast<size_t>(k)])) {
          fr[t] = 1;
          break;
        }
  }
}

bool CcdVoxelCulling::share_voxel(Index i, Index f, Index j, Index g) const {
  const auto& oi = offsets_[static_cast<size_t>(i)];
  const auto& oj = offsets_[static_cast<size_t>(j)];
  const std::int64_t* a = voxel_ids_[static_cast<size_t>(i)].data() + oi[static_cast<size_t>(f)];
  const std::int64_t* ae = voxel_ids_[static_cast<size_t>(i)].data() + oi[static_cast<size_t>(f) + 1];
  const std::int64_t* b = voxel_ids_[static_cast<size_t>(j)].data() + oj[static_cast<size_t>(g)];
  const std::int64_t* be = voxel_ids_[static_cast<size_t>(j)].data() + oj[static_cast<size_t>(g) + 1];
  while (a != ae && b != be) {
    if (*a == *b) return true;
    if (*a < *b)
      ++a;
    else
      ++b;
  }
  return false;
}

}  // namespace vproxq
