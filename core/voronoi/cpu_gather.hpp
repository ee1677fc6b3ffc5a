#pragma once
// Shared by the CPU Stage II backends (cpu_backend.cpp, cpu_self_backend.cpp): the triangles
// prepared once per call, and the walk over the bins around a sample point that visits each
// triangle once.
#include "core/geometry/point_triangle.hpp"
#include "core/parallel.hpp"
#include "core/voronoi/bins.hpp"

#include <algorithm>
#include <array>
#include <cstdlib>
#include <memory>
#include <vector>

namespace vproxq {

/// Bounding-box prefilter slack of the CPU backends, relative to the grid extent. A triangle
/// is skipped when the distance from the sample point to its bounding box exceeds the current
/// cut-off by more than kCpuPrefilterSlack * (grid extent). The box distance is within
/// ~4 * 2^-53 * extent of its exact value, point_triangle_distance() is never below the exact
/// distance by more than ~10 * 2^-53 * extent (its candidates are points of the triangle up to
/// rounding; the projection onto the plane counts where it is inside, or where rounding leaves
/// that in doubt, within a few 2^-53 of the coordinates of the triangle: point_triangle.cpp's
/// decide_face), and the exact box distance never exceeds the exact triangle distance, so a
/// skipped triangle's computed distance is strictly above the cut-off: skipping it never
/// changes the result.
inline constexpr double kCpuPrefilterSlack = 0x1p-30;

/// The prefilter slack for `grid` (see kCpuPrefilterSlack).
inline double cpu_prefilter_slack(const VoronoiGrid& grid) {
  return kCpuPrefilterSlack * grid.cell *
         static_cast<double>(grid.dims[0] + grid.dims[1] + grid.dims[2]);
}

/// Per triangle of a DvdInput: prepared corners and bounding box; with `entry_masks`, what
/// for_each_in() needs to visit each triangle once.
struct GatherTriangles {
  /// Default-initialised, then filled: a std::vector would zero its 200 bytes per triangle
  /// first (value-initialisation): about 2.5% of the inter-object Stage II's instructions on
  /// blobs-200.
  std::unique_ptr<PreparedTriangle[]> prepared;
  std::vector<Vec3> box_lo, box_hi;
  /// With `entry_masks`, per entry of in.bin_tris: bit a set when the entry's bin is its
  /// triangle's first bin along axis a (the first bin its box overlaps), so that for_each_in()
  /// decides a first visit from the bin list alone.
  std::vector<std::uint8_t> entry_starts;

  GatherTriangles(const DvdInput& in, int threads, bool entry_masks = false) {
    const std::size_t n = in.tri_site.size();
    prepared.reset(new PreparedTriangle[n]);
    box_lo.resize(n);
    box_hi.resize(n);
    parallel_for(n, threads, [&](std::size_t t) {
      const double* c = &in.tri_xyz_d[9 * t];
      const Triangle tri{Vec3(c[0], c[1], c[2]), Vec3(c[3], c[4], c[5]), Vec3(c[6], c[7], c[8])};
      prepared[t] = prepare_triangle(tri);
      box_lo[t] = tri[0].cwiseMin(tri[1]).cwiseMin(tri[2]);
      box_hi[t] = tri[0].cwiseMax(tri[1]).cwiseMax(tri[2]);
    });
    if (!entry_masks) return;
    std::vector<std::array<std::int32_t, 3>> first_bin(n);
    parallel_for(n, threads, [&](std::size_t t) { first_bin[t] = bins_overlapping(in, box_lo[t], box_hi[t]).lo; });
    entry_starts.resize(in.bin_tris.size());
    const std::size_t bx = static_cast<std::size_t>(in.bin_dims[0]), by = static_cast<std::size_t>(in.bin_dims[1]);
    parallel_for(in.bin_offsets.size() - 1, threads, [&](std::size_t b) {
      const std::array<std::int32_t, 3> here{static_cast<std::int32_t>(b % bx), static_cast<std::int32_t>((b / bx) % by),
                                             static_cast<std::int32_t>(b / (bx * by))};
      for (std::int32_t i = in.bin_offsets[b]; i < in.bin_offsets[b + 1]; ++i) {
        const auto& first = first_bin[static_cast<std::size_t>(in.bin_tris[static_cast<std::size_t>(i)])];
        entry_starts[static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(
            (first[0] == here[0]) | (first[1] == here[1]) << 1 | (first[2] == here[2]) << 2);
      }
    });
  }

  /// Squared distance from q to triangle t's bounding box.
  double box_distance_squared(std::size_t t, const Vec3& q) const {
    return (box_lo[t] - q).cwiseMax(q - box_hi[t]).cwiseMax(0.0).squaredNorm();
  }

  /// Calls visit(t) once for every triangle listed in the bins of `range`: in the first bin
  /// of the range holding it, the bin whose coordinate along each axis is the larger of the
  /// range's start and the triangle's first bin. Needs the entry masks.
  template <typename Visit>
  void for_each_in(const DvdInput& in, const BinRange& range, const Visit& visit) const {
    for (std::int32_t bz = range.lo[2]; bz <= range.hi[2]; ++bz)
      for (std::int32_t by = range.lo[1]; by <= range.hi[1]; ++by)
        for (std::int32_t bx = range.lo[0]; bx <= range.hi[0]; ++bx) {
          const auto b = static_cast<std::size_t>(bin_id(in, bx, by, bz));
          // Along an axis where this bin is past the range's start, only triangles whose
          // first bin it is are visited here (the others were visited in an earlier bin).
          const auto need = static_cast<std::uint8_t>((bx > range.lo[0]) | (by > range.lo[1]) << 1 |
                                                      (bz > range.lo[2]) << 2);
          for (std::int32_t i = in.bin_offsets[b]; i < in.bin_offsets[b + 1]; ++i)
            if ((entry_starts[static_cast<std::size_t>(i)] & need) == need)
              visit(static_cast<std::size_t>(in.bin_tris[static_cast<std::size_t>(i)]));
        }
  }
};

/// Triangle ids [lo, hi) that a walk passes over without visiting them (empty: none).
struct SkippedTriangles {
  std::int32_t lo = 0, hi = 0;
};

/// The ids of `site`'s triangles when they are consecutive, which they are when tri_site is
/// non-decreasing (Stage II lists triangles in object order), else none (`sorted`: whether
/// in.tri_site is non-decreasing, checked once per call by the caller).
inline SkippedTriangles site_triangles(const DvdInput& in, bool sorted, std::int32_t site) {
  if (!sorted || site < 0) return {};
  const auto lo = std::lower_bound(in.tri_site.begin(), in.tri_site.end(), site);
  const auto hi = std::upper_bound(lo, in.tri_site.end(), site);
  return {static_cast<std::int32_t>(lo - in.tri_site.begin()),
          static_cast<std::int32_t>(hi - in.tri_site.begin())};
}

/// Calls visit(t) for the triangles listed in the bins of `range`, bins in rings of increasing
/// Chebyshev distance around the bin of q, each triangle at most once per `stamp` (`seen` holds
/// the last stamp per triangle; it grows as needed; a stamp must never repeat). Stops before a
/// ring all of whose points are farther from q than cutoff() (+ the relative slack below), and
/// passes over a bin whose box is farther from q than cutoff() (+ a slack for the rounding of
/// its bounds), so every triangle having a point within cutoff() of q is visited, whatever
/// cutoff() returns while the walk goes on (it may only shrink): such a point lies in a bin
/// that lists the triangle and is no farther from q. Triangles in `skip` are not visited: each
/// bin's list is sorted (bins.cpp fills them in triangle order), so they are one run per bin,
/// found by binary search instead of being stepped over one by one.
template <typename Cutoff, typename Visit>
void for_each_nearest_first(const DvdInput& in, const Vec3& q,
                            const BinRange& range, std::vector<std::uint64_t>& seen,
                            std::uint64_t stamp, const Cutoff& cutoff, const Visit& visit,
                            SkippedTriangles skip = {}) {
  if (seen.size() < in.tri_site.size()) seen.resize(in.tri_site.size(), 0);
  std::array<std::int32_t, 3> c{};
  std::int32_t rings = 0;
  for (int a = 0; a < 3; ++a) {
    const auto k = static_cast<std::size_t>(a);
    c[k] = std::clamp(bin_coordinate(in, a, q[a]), range.lo[k], range.hi[k]);
    rings = std::max({rings, c[k] - range.lo[k], range.hi[k] - c[k]});
  }
  // A bin r rings away is separated from q's bin by r - 1 whole bins along some axis.
  const double width = in.grid.cell * in.bin_size;
  // Bin b along an axis holds the coordinates x with floor(x / cell) / bin_size == b: up to the
  // rounding of x / cell, [b width, (b + 1) width), the first and last bins unbounded (clamped
  // coordinates). The computed bounds and gaps are within a few 2^-53 of (|q| + bin bounds) of
  // their exact values, so widening the cut-off by 2^-40 of that never passes over a bin
  // holding a point within cutoff() of q.
  const double bound_slack = kBinSearchSlack * (q.cwiseAbs().maxCoeff() + width * (1 + std::max({in.bin_dims[0], in.bin_dims[1], in.bin_dims[2]})));
  auto gap = [&](int a, std::int32_t b) {
    const double lo = b * width - q[a], hi = q[a] - (b + 1) * width;
    return std::max({b > 0 ? lo : 0.0, b + 1 < in.bin_dims[static_cast<std::size_t>(a)] ? hi : 0.0, 0.0});
  };
  // Whether a bin (or row of bins) whose squared gaps along the other axes sum to g2 may hold
  // a point within cutoff() of q.
  auto in_reach = [&](double g2) {
    const double reach = cutoff() + bound_slack;
    return g2 <= reach * reach;
  };
  // g2: the squared gaps along y and z of the bin's row.
  auto visit_bin = [&](std::int32_t bx, std::int32_t by, std::int32_t bz, double g2) {
    const double gx = gap(0, bx);
    if (!in_reach(g2 + gx * gx)) return;
    const auto b = static_cast<std::size_t>(bin_id(in, bx, by, bz));
    const std::int32_t* first = in.bin_tris.data() + in.bin_offsets[b];
    const std::int32_t* last = in.bin_tris.data() + in.bin_offsets[b + 1];
    auto visit_run = [&](const std::int32_t* p, const std::int32_t* e) {
      for (; p != e; ++p) {
        const auto t = static_cast<std::size_t>(*p);
        if (seen[t] == stamp) continue;
        seen[t] = stamp;
        visit(t);
      }
    };
    if (skip.lo >= skip.hi) {
      visit_run(first, last);
      return;
    }
    // A bin holding only skipped triangles (ascending: its first and last say so) or none.
    if (first == last || (*first >= skip.lo && last[-1] < skip.hi)) return;
    const std::int32_t* s0 = std::lower_bound(first, last, skip.lo);
    visit_run(first, s0);
    visit_run(std::lower_bound(s0, last, skip.hi), last);
  };
  for (std::int32_t r = 0; r <= rings; ++r) {
    if (r >= 2 && (r - 1) * width > cutoff() * (1 + 0x1p-20)) break;
    const std::int32_t z0 = std::max(range.lo[2], c[2] - r), z1 = std::min(range.hi[2], c[2] + r);
    const std::int32_t y0 = std::max(range.lo[1], c[1] - r), y1 = std::min(range.hi[1], c[1] + r);
    const std::int32_t x0 = std::max(range.lo[0], c[0] - r), x1 = std::min(range.hi[0], c[0] + r);
    for (std::int32_t bz = z0; bz <= z1; ++bz) {
      const double gz = gap(2, bz);
      if (!in_reach(gz * gz)) continue;
      for (std::int32_t by = y0; by <= y1; ++by) {
        const double gy = gap(1, by), g2 = gy * gy + gz * gz;
        if (!in_reach(g2)) continue;
        const bool shell = std::abs(bz - c[2]) == r || std::abs(by - c[1]) == r;
        if (shell) {
          for (std::int32_t bx = x0; bx <= x1; ++bx) visit_bin(bx, by, bz, g2);
        } else {
          if (c[0] - r >= range.lo[0]) visit_bin(c[0] - r, by, bz, g2);
          if (r > 0 && c[0] + r <= range.hi[0]) visit_bin(c[0] + r, by, bz, g2);
        }
      }
    }
  }
}

}  // namespace vproxq
