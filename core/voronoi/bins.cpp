#include "core/voronoi/bins.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>
#include <string>

namespace vproxq {

std::int32_t bin_coordinate(const DvdInput& in, int axis, double x) {
  const std::int32_t dim = in.grid.dims[static_cast<std::size_t>(axis)];
  // Clamp in double before converting: x / cell may be huge or infinite.
  const double voxel = std::clamp(std::floor(x / in.grid.cell), 0.0, static_cast<double>(dim - 1));
  return static_cast<std::int32_t>(voxel) / in.bin_size;
}

BinRange bins_overlapping(const DvdInput& in, const Vec3& lo, const Vec3& hi) {
  BinRange range;
  for (int axis = 0; axis < 3; ++axis) {
    const auto a = static_cast<std::size_t>(axis);
    range.lo[a] = bin_coordinate(in, axis, lo[axis]);
    range.hi[a] = bin_coordinate(in, axis, hi[axis]);
  }
  return range;
}

BinRange bins_within(const DvdInput& in, const Vec3& point, double radius) {
  // fl(point - r) can exceed the exact point - r by half an ulp of |point| + r; the widening is
  // 2^13 times that. With an infinite radius the box is the whole grid.
  const double widened = radius + kBinSearchSlack * (point.cwiseAbs().maxCoeff() + radius);
  const Vec3 r = Vec3::Constant(widened);
  return bins_overlapping(in, point - r, point + r);
}

std::int32_t bin_size_for(const VoronoiGrid& grid, std::int32_t preferred) {
  auto bins = [&](std::int64_t side) {
    std::int64_t n = 1;
    for (const std::int32_t d : grid.dims) n *= (std::int64_t{d} + side - 1) / side;
    return n;
  };
  std::int64_t side = std::max<std::int32_t>(preferred, 1);
  while (bins(side) > kMaxBins) ++side;
  return static_cast<std::int32_t>(side);
}

void set_bin_layout(DvdInput& in, std::int32_t bin_size) {
  if (bin_size < 1) {
    throw std::invalid_argument("bin_triangles: bin_size " + std::to_string(bin_size) +
                                " is not positive");
  }
  in.bin_size = bin_size;
  for (std::size_t a = 0; a < 3; ++a) in.bin_dims[a] = (in.grid.dims[a] + bin_size - 1) / bin_size;
}

std::vector<std::uint8_t> reached_bins(const DvdInput& in) {
  std::vector<std::uint8_t> reached(static_cast<std::size_t>(in.bin_dims[0]) *
                                    static_cast<std::size_t>(in.bin_dims[1]) *
                                    static_cast<std::size_t>(in.bin_dims[2]), 0);
  // In whole voxels: a sample at voxel v (centre (v + 1/2) cell) with band r visits the bins of
  // voxels floor(v + 1/2 -+ x) with x = r' / cell, r' = r widened by kBinSearchSlack
  // (bins_within()), up to the rounding of that expression, a few 2^-53 of its magnitude (at
  // most the grid's dims): below 1e-6. Those voxels lie within v -+ k for k = floor(x + 1/2 +
  // 1e-6) (floor(v + 1/2 + x + e) <= v + k, and floor(v + 1/2 - x - e) >= v - k since
  // floor(y) + 1 > y). So marking the bins of v -+ k marks a superset.
  const std::int32_t max_dim = std::max({in.grid.dims[0], in.grid.dims[1], in.grid.dims[2]});
  const double extent = in.grid.cell * max_dim;
  BinRange last;
  bool any = false;
  for (std::size_t k = 0; k < in.voxels.size(); ++k) {
    const double widened = in.band[k] + kBinSearchSlack * (2 * extent + in.band[k]);
    const double cells = std::floor(widened / in.grid.cell + 0.5 + 1e-6);
    const std::int64_t reach = cells < max_dim ? static_cast<std::int64_t>(cells) : max_dim;
    const std::int64_t id = in.voxels[k];
    const std::array<std::int64_t, 3> v{id % in.grid.dims[0], (id / in.grid.dims[0]) % in.grid.dims[1],
                                        id / (std::int64_t{in.grid.dims[0]} * in.grid.dims[1])};
    BinRange r;
    for (std::size_t a = 0; a < 3; ++a) {
      r.lo[a] = static_cast<std::int32_t>(std::max<std::int64_t>(v[a] - reach, 0) / in.bin_size);
      r.hi[a] = static_cast<std::int32_t>(std::min<std::int64_t>(v[a] + reach, in.grid.dims[a] - 1) / in.bin_size);
    }
    // Neighbouring samples (the voxels are sorted) mostly reach the same bins.
    if (any && r.lo == last.lo && r.hi == last.hi) continue;
    any = true;
    last = r;
    for (std::int32_t z = r.lo[2]; z <= r.hi[2]; ++z)
      for (std::int32_t y = r.lo[1]; y <= r.hi[1]; ++y)
        for (std::int32_t x = r.lo[0]; x <= r.hi[0]; ++x) reached[static_cast<std::size_t>(bin_id(in, x, y, z))] = 1;
  }
  return reached;
}

bool reaches(const DvdInput& in, const std::vector<std::uint8_t>& reached, const BinRange& r) {
  for (std::int32_t z = r.lo[2]; z <= r.hi[2]; ++z)
    for (std::int32_t y = r.lo[1]; y <= r.hi[1]; ++y)
      for (std::int32_t x = r.lo[0]; x <= r.hi[0]; ++x)
        if (reached[static_cast<std::size_t>(bin_id(in, x, y, z))]) return true;
  return false;
}

void bin_triangles(DvdInput& in, std::int32_t bin_size) {
  set_bin_layout(in, bin_size);
  if (in.tri_xyz_d.size() % 9 != 0) {
    throw std::invalid_argument("bin_triangles: tri_xyz_d has " +
                                std::to_string(in.tri_xyz_d.size()) +
                                " numbers, not 9 per triangle");
  }
  const std::size_t bin_count = static_cast<std::size_t>(in.bin_dims[0]) *
                                static_cast<std::size_t>(in.bin_dims[1]) *
                                static_cast<std::size_t>(in.bin_dims[2]);
  const std::size_t tri_count = in.tri_xyz_d.size() / 9;

  // Each triangle's bin range, from its bounding box in double.
  std::vector<BinRange> ranges(tri_count);
  for (std::size_t t = 0; t < tri_count; ++t) {
    const double* c = &in.tri_xyz_d[9 * t];
    Vec3 lo, hi;
    for (int k = 0; k < 3; ++k) {
      lo[k] = std::min({c[k], c[3 + k], c[6 + k]});
      hi[k] = std::max({c[k], c[3 + k], c[6 + k]});
    }
    ranges[t] = bins_overlapping(in, lo, hi);
  }

  // Counting pass, prefix sum, filling pass in triangle order (so each bin is sorted).
  std::vector<std::int64_t> counts(bin_count + 1, 0);
  auto for_each_bin = [&](const BinRange& r, auto&& f) {
    for (std::int32_t z = r.lo[2]; z <= r.hi[2]; ++z)
      for (std::int32_t y = r.lo[1]; y <= r.hi[1]; ++y)
        for (std::int32_t x = r.lo[0]; x <= r.hi[0]; ++x)
          f(static_cast<std::size_t>(bin_id(in, x, y, z)));
  };
  for (const BinRange& r : ranges) for_each_bin(r, [&](std::size_t b) { ++counts[b + 1]; });
  for (std::size_t b = 0; b < bin_count; ++b) counts[b + 1] += counts[b];
  if (counts[bin_count] > std::numeric_limits<std::int32_t>::max()) {
    throw std::invalid_argument("bin_triangles: " + std::to_string(counts[bin_count]) +
                                " bin entries exceed the 32-bit offsets; use larger bins");
  }
  in.bin_offsets.assign(counts.begin(), counts.end());
  in.bin_tris.assign(static_cast<std::size_t>(counts[bin_count]), 0);
  std::vector<std::int64_t> cursor(counts.begin(), counts.end() - 1);
  for (std::size_t t = 0; t < tri_count; ++t) {
    for_each_bin(ranges[t], [&](std::size_t b) {
      in.bin_tris[static_cast<std::size_t>(cursor[b]++)] = static_cast<std::int32_t>(t);
    });
  }
}

void validate_dvd_input(const DvdInput& in) {
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("DiscreteVoronoiBackend::compute: " + what);
  };
  if (!(in.grid.cell > 0.0) || !std::isfinite(in.grid.cell)) fail("grid cell must be positive");
  const std::size_t tris = in.tri_site.size();
  if (in.tri_xyz_d.size() != 9 * tris) fail("tri_xyz_d is not 9 numbers per triangle");
  if (in.band.size() != in.voxels.size()) fail("band and voxels differ in size");
  if (!in.exclude_site.empty() && in.exclude_site.size() != in.voxels.size())
    fail("exclude_site is neither empty nor one per voxel");
  if (in.bin_size < 1) fail("bin_size < 1 (call bin_triangles())");
  const std::size_t bins = static_cast<std::size_t>(in.bin_dims[0]) *
                           static_cast<std::size_t>(in.bin_dims[1]) *
                           static_cast<std::size_t>(in.bin_dims[2]);
  for (std::size_t a = 0; a < 3; ++a) {
    if (in.grid.dims[a] < 1) fail("grid dims must be positive");
    if (in.bin_dims[a] != (in.grid.dims[a] + in.bin_size - 1) / in.bin_size) {
      fail("bin_dims do not match grid dims and bin_size (call bin_triangles())");
    }
  }
  if (in.bin_offsets.size() != bins + 1 || in.bin_offsets.front() != 0 ||
      static_cast<std::size_t>(in.bin_offsets.back()) != in.bin_tris.size()) {
    fail("bin_offsets is not a CSR offset array over bin_dims (call bin_triangles())");
  }
  if (!std::is_sorted(in.bin_offsets.begin(), in.bin_offsets.end())) {
    fail("bin_offsets decrease somewhere");
  }
  for (const std::int32_t t : in.bin_tris) {
    if (t < 0 || static_cast<std::size_t>(t) >= tris) fail("bin_tris holds an invalid triangle");
  }
  for (std::size_t b = 0; b < bins; ++b) {
    if (!std::is_sorted(in.bin_tris.begin() + in.bin_offsets[b],
                        in.bin_tris.begin() + in.bin_offsets[b + 1]))
      fail("a bin's triangles are not in ascending order (call bin_triangles())");
  }
  const std::int64_t voxel_count = in.grid.voxel_count();
  for (std::size_t k = 0; k < in.voxels.size(); ++k) {
    if (in.voxels[k] < 0 || in.voxels[k] >= voxel_count) fail("voxel id outside the grid");
    if (!(in.band[k] >= 0.0f)) fail("band must be >= 0 (NaN is not allowed)");
  }
}

}  // namespace vproxq
