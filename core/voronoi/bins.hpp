#pragma once
// Triangle binning for the Stage II backends (DvdInput::bin_*): a coarse uniform grid over the
// voxel grid, each bin listing the triangles whose bounding box overlaps it, so that a sample
// point only looks at the triangles near it.
//
// Exactness: a coordinate x (relative to the grid origin) lies in voxel floor(x / cell) and in
// bin floor(x / cell) / bin_size, both clamped to the grid (bin_coordinate()). That map is
// monotone in x, also in floating point, so a triangle that has a point inside a box overlaps
// (in bin space) the bins of that box: visiting bins_overlapping(box) finds it. Rounding enters
// only where the box is computed from a point and a radius; bins_within() widens the box by
// enough to absorb it.
#include <array>
#include <cstdint>
#include <vector>

#include "core/voronoi/discrete_voronoi.hpp"

namespace vproxq {

/// Fills in.bin_size, in.bin_dims (ceil(grid dims / bin_size) per axis), in.bin_offsets and
/// in.bin_tris (CSR) from in.tri_xyz_d and in.grid: every triangle is listed in every bin its
/// axis-aligned bounding box overlaps (clamped to the grid), in increasing triangle order
/// within a bin. Throws std::invalid_argument when bin_size < 1, when tri_xyz_d is not 9
/// numbers per triangle, or when the listing would exceed 2^31 - 1 entries.
void bin_triangles(DvdInput& in, std::int32_t bin_size);

/// Sets in.bin_size and in.bin_dims as bin_triangles() does, without listing any triangle (for
/// reached_bins() before the triangles are chosen). Throws std::invalid_argument when
/// bin_size < 1.
void set_bin_layout(DvdInput& in, std::int32_t bin_size);

/// Bins at most (2^24 bins: the CSR offsets are dense, 12 bytes per bin while binning).
inline constexpr std::int64_t kMaxBins = std::int64_t{1} << 24;

/// The bin side (voxels) to use for `grid`: `preferred`, or the smallest larger side that keeps
/// the bin count within kMaxBins (fine grids: --grid 2048 would otherwise need 134 M bins).
/// Any side is correct; larger bins only make each sample point look at more triangles.
std::int32_t bin_size_for(const VoronoiGrid& grid, std::int32_t preferred);

/// Checks what the backends rely on: 9 coordinates and a site per triangle, a band (>= 0, not
/// NaN) per sample voxel, voxel ids inside the grid, and a CSR binning consistent with the grid
/// (as bin_triangles() makes it). Throws std::invalid_argument naming the problem. Sortedness
/// and uniqueness of the voxels are not checked: the backends do not depend on them.
void validate_dvd_input(const DvdInput& in);

/// Inclusive ranges of bin coordinates, per axis. Never empty: bins are clamped to the grid.
struct BinRange {
  std::array<std::int32_t, 3> lo{0, 0, 0};
  std::array<std::int32_t, 3> hi{0, 0, 0};
};

/// Bin coordinate along `axis` of coordinate `x` (relative to the grid origin):
/// clamp(floor(x / cell), 0, dims[axis] - 1) / bin_size. Monotone in x; +-infinity clamp to
/// the first / last bin. `x` must not be NaN.
std::int32_t bin_coordinate(const DvdInput& in, int axis, double x);

/// Bins overlapping the box [lo, hi] (relative to the grid origin), clamped to the grid.
BinRange bins_overlapping(const DvdInput& in, const Vec3& lo, const Vec3& hi);

/// Centre of voxel `id`, relative to the grid origin: cell * (index + 0.5), as every backend
/// computes it.
inline Vec3 voxel_centre(const VoronoiGrid& grid, std::int64_t id) {
  const std::int64_t x = id % grid.dims[0];
  const std::int64_t y = (id / grid.dims[0]) % grid.dims[1];
  const std::int64_t z = id / (std::int64_t{grid.dims[0]} * grid.dims[1]);
  return grid.cell * Vec3(static_cast<double>(x) + 0.5, static_cast<double>(y) + 0.5,
                          static_cast<double>(z) + 0.5);
}

/// Per bin of in's layout (set_bin_layout()), 1 where some sample's walk may look: every bin
/// of bins_within(voxel_centre(in.voxels[k]), in.band[k]) of every sample k (and some bins
/// beside them: the ranges are taken in whole voxels around the sample's). A backend reports,
/// for a sample, only triangles closer than its band, and every such triangle's box overlaps
/// one of those bins; so a triangle whose box overlaps no reached bin can be left out of the
/// input without changing any output (Stage II leaves them out: most of a frame's triangles
/// are far from every sample).
std::vector<std::uint8_t> reached_bins(const DvdInput& in);

/// Whether the range holds a bin that reached_bins() marked.
bool reaches(const DvdInput& in, const std::vector<std::uint8_t>& reached, const BinRange& range);

/// The bins to visit to find every triangle (in double coordinates tri_xyz_d) that has a point
/// within distance `radius` of `point` (closed ball): bins_overlapping() of the box
/// point -+ radius, widened by kBinSearchSlack * (|point|_inf + radius) so that the rounding of
/// point -+ radius can never shrink it. `radius` >= 0 and may be +infinity.
BinRange bins_within(const DvdInput& in, const Vec3& point, double radius);

/// Relative widening of bins_within()'s box: 2^-40, far above the one rounding (2^-53
/// relative) of each box bound, and far below anything that changes the bins visited in
/// practice.
inline constexpr double kBinSearchSlack = 0x1p-40;

/// Linear id of bin (x, y, z): x + bin_dims[0] * (y + bin_dims[1] * z).
inline std::int64_t bin_id(const DvdInput& in, std::int32_t x, std::int32_t y, std::int32_t z) {
  return x + std::int64_t{in.bin_dims[0]} * (y + std::int64_t{in.bin_dims[1]} * z);
}

}  // namespace vproxq
