#pragma once
// Stage II host side (paper 4.4, 5.2, 5.2.1): grid, conservative voxelization of the sites,
// bands from Stage I, a backend's 2nd-order DVD at the sample points, and from it the distance
// bounds of Lemma 2: D_u per object and D_l per triangle.
#include "core/broad_phase/object_broad_phase.hpp"
#include "core/voronoi/discrete_voronoi.hpp"

#include <cstdint>
#include <vector>

namespace vproxq {

/// Bands are capped at this many cells of the grid, or of the default grid
/// (default_grid_resolution()) where those are larger: a narrower band only weakens culling,
/// never correctness (values at the cap give D_l = cap - δ, which culls only where D_u fell
/// below cap - δ). A capped band culls where the object's SD~ + 2δ (δ ~ 0.87 cell) lies below
/// it, so 2 cells keep the culling of objects nearer than ~0.27 cell to another, 3 cells that
/// of objects up to ~1.27 cells away. Measured (cpu backend, 2 threads), 3 -> 2 cells: the
/// 200-object scene's inter-object distance 31-34 -> 23-26 ms per frame (two runs each,
/// bench.sh's frames, best of 5) with 0.9% more exact tests on frame 2 and the same on the
/// others; the report scenes' frames 10-15, exact tests +6% on skirt (2,262 -> 2,392 per
/// frame), +1% on funnel, the same on cloth-ball and breaking, and Stage II 5-10% faster
/// (skirt's query time within its run-to-run spread). 1.5 cells: 20-22 ms, skirt +37%.
/// On grids finer than the default, a cap of 2 of their own cells shrank the band in scene
/// units until it culled nothing: skirt's frames 10-12 had 2,743 / 5,443 / 8,948 inter-object
/// exact tests per frame at --grid 128 / 256 / 512 (off: 9,530); with 2 default cells (the
/// default grid has 92 cells there) 2,292 / 1,428 / 778, for 26 / 116 / 968 ms of Stage II
/// instead of 22 / 59 / 208 (see docs/algorithms.md, "Stage II"); 23 / 71 / 249 ms since the bins are
/// twice the cap wide on such grids (stage2.cpp).
inline constexpr double kMaxInterBandCells = 2.0;

/// Grid resolution used when none is given: 4 * cbrt(triangles), clamped to [32, 256] cells
/// along the longest axis (paper fig. 14: the best resolution grows with scene complexity).
int default_grid_resolution(std::int64_t triangles);

struct VoronoiBounds {
  VoronoiGrid grid;
  double delta = 0;            ///< δ = (cell diagonal)/2 + voxelization slack + δ_precision
  double delta_precision = 0;  ///< the backend's float error bound for this grid
  /// The bands' cap: kMaxInterBandCells cells of the grid or of the default grid, the larger.
  double band_cap = 0;
  /// D_u(O_i) = min(Stage I bound, SD~(O_i) + δ): the separation distance of object i is at
  /// most this.
  std::vector<double> object_upper;
  /// D_l(f) = SD~(f) - δ per triangle: f is at least this far from every other object.
  std::vector<std::vector<double>> triangle_lower;
  std::uint64_t sample_voxels = 0;
  /// Triangles with samples: those whose box lies within min(U_i + 2 slack, band) of another
  /// object's triangle box (the others get that as D_l without a sample).
  std::uint64_t sampled_triangles = 0;
  /// Triangles passed to the backend: those some sample's walk can reach (reachable_triangles()).
  std::uint64_t backend_triangles = 0;
  double setup_ms = 0, upload_ms = 0, compute_ms = 0, readback_ms = 0, scan_ms = 0;
};

/// Runs Stage II on a frame. `grid_resolution` <= 0 picks default_grid_resolution().
VoronoiBounds compute_voronoi_bounds(const Frame& frame, const FrameBoxes& boxes,
                                     const ObjectBroadPhase& stage1,
                                     DiscreteVoronoiBackend& backend, int grid_resolution,
                                     int threads);

}  // namespace vproxq
