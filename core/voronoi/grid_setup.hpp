#pragma once
// Pieces shared by the inter-object (stage2.cpp) and the intra-object (self_stage2.cpp) Stage II:
// the grid over the scene, the conservative voxelization of a triangle, and the triangle arrays
// of a DvdInput.
#include "core/broad_phase/aabb.hpp"
#include "core/broad_phase/object_broad_phase.hpp"
#include "core/geometry/triangle_box.hpp"
#include "core/scene.hpp"
#include "core/voronoi/discrete_voronoi.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <functional>
#include <limits>
#include <utility>
#include <vector>

namespace vproxq {

/// A Stage II grid and the numbers Lemma 2 derives from it.
struct StageGrid {
  VoronoiGrid grid;
  /// Length of the grid box's diagonal: every coordinate relative to the origin (triangle
  /// corners inside the box, sample points) is at most this in magnitude.
  double extent = 0;
  /// Voxelization slack: the SAT test runs in double on coordinates relative to the grid
  /// origin, of magnitude <= extent; its projections are off by at most a few ulps of it.
  /// Widening the voxel's half side by kVoxelSlackRel * (extent + cell) (~4.5e6 ulps) makes the
  /// test conservative: every voxel that the exact triangle touches is marked. A marked voxel
  /// centre is then within `half` * sqrt(3) of the triangle, which δ accounts for.
  double voxel_slack = 0;
  double half = 0;  ///< cell / 2 + voxel_slack
  /// The backends' length unit, a power of two with extent / unit in [0.5, 1): a backend gets
  /// every length (coordinates relative to the origin, cell, bands) divided by it and returns
  /// distances in it, so its float32 arithmetic sees numbers of magnitude about 1 whatever the
  /// scene's scale (at 1e-50 or 1e50 plain float32 would underflow to 0 or overflow to inf).
  /// Dividing and multiplying by a power of two is exact in double.
  double unit = 1;

  static constexpr double kVoxelSlackRel = 1e-9;
  /// voxelize_cells() finds the span of rows of more than this many cells.
  static constexpr std::int32_t kRowSpanCells = 3;

  /// Cubic cells, `resolution` (>= 1) cells along the longest axis of the non-empty `box`.
  static StageGrid over(const AABB& box, int resolution) {
    StageGrid g;
    const Vec3 ext = box.hi - box.lo;
    // A box of zero extent (every point at one place) still gets cells whose squares, in
    // extent below, do not underflow to 0 (which would make `unit` 0).
    const double longest = std::max(ext.maxCoeff(), 0x1p-400);
    // `resolution` cells cover the longest axis: the quotient rounded down would need one more
    // (--grid 50 gave 51 cells on a scene), so the cell is rounded up until they do.
    g.grid.cell = longest / resolution;
    while (g.grid.cell * resolution < longest) g.grid.cell = std::nextafter(g.grid.cell, kInfinity);
    g.grid.origin = box.lo;
    for (int k = 0; k < 3; ++k)
      g.grid.dims[k] = std::clamp<std::int32_t>(static_cast<std::int32_t>(std::ceil(ext[k] / g.grid.cell)), 1, resolution);
    g.extent = (g.grid.cell * Vec3(g.grid.dims[0], g.grid.dims[1], g.grid.dims[2])).norm();
    g.voxel_slack = kVoxelSlackRel * (g.extent + g.grid.cell);
    g.half = 0.5 * g.grid.cell + g.voxel_slack;
    g.unit = std::ldexp(1.0, std::ilogb(g.extent) + 1);
    return g;
  }

  /// The grid as the backends get it: origin 0 (their coordinates are relative to
  /// grid.origin) and the cell in backend units.
  VoronoiGrid backend_grid() const {
    VoronoiGrid g = grid;
    g.origin = Vec3::Zero();
    g.cell = grid.cell / unit;
    return g;
  }

  /// δ_precision in scene units: the backend's error bound for the extent in its units,
  /// scaled back.
  template <typename Backend>
  double delta_precision(const Backend& backend) const {
    return unit * backend.distance_error_bound(extent / unit);
  }

  /// Coordinate x along axis k in backend units, relative to the origin: every triangle corner
  /// and box bound a backend sees goes through this one monotone map.
  double backend_coord(double x, int k) const { return (x - grid.origin[k]) / unit; }

  /// `length` (scene units) as a float in backend units, rounded up: never below the double.
  float backend_band(double length) const {
    const float f = static_cast<float>(length / unit);
    return static_cast<double>(f) >= length / unit ? f : std::nextafter(f, std::numeric_limits<float>::infinity());
  }

  /// Lemma 2's δ: the farthest a marked voxel centre is from its triangle, plus the backend's
  /// arithmetic error.
  double delta(double delta_precision) const { return std::sqrt(3.0) * half + delta_precision; }

  /// Calls visit(linear voxel id) for every voxel that `tri` (absolute coordinates, bounding
  /// box `box`) touches, conservatively (see voxel_slack), in increasing (z, y, x) order.
  template <typename Visit>
  void voxelize(const Triangle& tri, const AABB& box, const Visit& visit) const {
    voxelize_cells(tri, box, [&](const Cell&, std::int64_t id) { visit(id); });
  }

  using Cell = std::array<std::int32_t, 3>;
  /// The cells voxelize() visits for a triangle with bounding box `box` lie in this range
  /// (inclusive); so do those of every triangle whose box lies inside `box`.
  std::pair<Cell, Cell> cell_range(const AABB& box) const {
    Cell lo{}, hi{};
    for (int k = 0; k < 3; ++k) {
      // Clamped in double before the conversion: an empty box's infinite bounds (an object
      // without triangles) must not reach the int conversion.
      auto cell_of = [&](double x) {
        return static_cast<std::int32_t>(std::clamp(std::floor(x / grid.cell), 0.0, static_cast<double>(grid.dims[k] - 1)));
      };
      lo[k] = cell_of(box.lo[k] - grid.origin[k] - voxel_slack);
      hi[k] = cell_of(box.hi[k] - grid.origin[k] + voxel_slack);
    }
    return {lo, hi};
  }

  /// voxelize(), calling visit(cell, linear id).
  template <typename Visit>
  void voxelize_cells(const Triangle& tri, const AABB& box, const Visit& visit) const {
    Triangle rel = tri;
    for (auto& p : rel) p -= grid.origin;
    const auto [lo, hi] = cell_range(box);
    const TriangleBoxTester tester(rel, half);
    // Per row of cells along x, only the cells within the row's span (row_span(), widened by a
    // cell on each side) are tested: on fine grids a triangle's box holds some cells per side,
    // and testing all of its cells cost the cube of that (skirt at --grid 1024: the inter- and
    // intra-object setups took 3.2 and 3.3 s per frame, 0.7 and 0.8 s this way). The cells
    // visited are the same: those that overlaps() accepts.
    // Rows shorter than kRowSpanCells + 1 cells are tested whole: finding the span costs more
    // than it saves there (blobs-200 at its default grid, triangles of 1-2 cells: +7% setup).
    double magnitude = extent + 2 * grid.cell;
    for (const auto& p : rel) magnitude = std::max(magnitude, p.cwiseAbs().maxCoeff());
    for (std::int32_t z = lo[2]; z <= hi[2]; ++z)
      for (std::int32_t y = lo[1]; y <= hi[1]; ++y) {
        const double cy = grid.cell * (y + 0.5), cz = grid.cell * (z + 0.5);
        std::int32_t first = lo[0], last = hi[0];
        if (last - first >= kRowSpanCells) {
          const auto [slo, shi] = tester.row_span(cy, cz, magnitude);
          if (!(slo <= shi)) continue;
          // Centre x of cell X is cell * (X + 1/2): the cells whose centres lie in the span,
          // one more on each side, clamped (in double: the span may be infinite) to the box's.
          const double f = std::max(std::ceil(slo / grid.cell - 0.5) - 1, static_cast<double>(lo[0]));
          const double l = std::min(std::floor(shi / grid.cell - 0.5) + 1, static_cast<double>(hi[0]));
          if (f > l) continue;
          first = static_cast<std::int32_t>(f);
          last = static_cast<std::int32_t>(l);
        }
        for (std::int32_t x = first; x <= last; ++x) {
          const Vec3 c = grid.cell * Vec3(x + 0.5, y + 0.5, z + 0.5);
          if (!tester.overlaps(c)) continue;
          visit(Cell{x, y, z}, x + std::int64_t{grid.dims[0]} * (y + std::int64_t{grid.dims[1]} * z));
        }
      }
  }
};

/// The median (the upper one, for an even count) of the longest sides of the triangle boxes of
/// the objects i with include(i); 0 when they have no triangle.
double median_triangle_side(const FrameBoxes& boxes, const std::function<bool(size_t)>& include);

/// Fills in.tri_xyz, in.tri_xyz_d (relative to sg.grid.origin, in backend units:
/// backend_coord()) and in.tri_site (object id) with the triangles kept[i] of each object i
/// (ascending), in object order.
void fill_dvd_triangles(DvdInput& in, const Frame& frame, const StageGrid& sg,
                        const std::vector<std::vector<Index>>& kept);

/// Per object i with wanted(i), its triangles (ascending) whose boxes overlap a bin that
/// reached_bins(in) marks, and those that also(i, t) asks for: the triangles a backend needs,
/// since it reports only triangles closer than a sample's band, whose boxes overlap one of the
/// bins the sample reaches. `in` needs its grid and bin layout (set_bin_layout()). The bins of
/// a box are those bin_triangles() computes for the triangle: its bounds are corners'
/// coordinates, mapped to backend units by the same backend_coord().
std::vector<std::vector<Index>> reachable_triangles(const DvdInput& in, const StageGrid& sg,
                                                    const FrameBoxes& boxes, int threads,
                                                    const std::function<bool(size_t)>& wanted,
                                                    const std::function<bool(size_t, Index)>& also);

}  // namespace vproxq
