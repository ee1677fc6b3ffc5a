// The CPU twin of the self Stage II backend: at every sample (voxel, triangle f), the distance
// from the voxel centre to the nearest triangle of f's object sharing no vertex with f, in
// double precision, multi-threaded over voxels.
//
// The samples of one voxel are consecutive, so each voxel is one work item: a triangle's
// distance to the voxel centre is computed once and offered to every sample of the voxel that
// may use it (same object, no shared vertex, below the sample's band). The per-sample result is
// the same as evaluating each sample on its own.
#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "core/geometry/point_triangle.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "core/voronoi/bins.hpp"
#include "core/voronoi/self_stage2.hpp"

namespace vproxq {
namespace {

// distance_error_bound(), in units of extent * 2^-24: the derivation of the inter-object CPU
// backend (cpu_backend.cpp, kCpuErrorBoundUnits) applies unchanged: same double point–triangle
// distance, same final rounding to float; the 1-ring exclusion only removes candidates.
constexpr double kCpuSelfErrorBoundUnits = 8.0;
// Bounding-box prefilter slack, relative to the grid extent: as in cpu_backend.cpp
// (kPrefilterSlack), a skipped triangle's computed distance is strictly above the cut-off.
constexpr double kPrefilterSlack = 0x1p-30;

class CpuSelfVoronoiBackend final : public SelfVoronoiBackend {
 public:
  explicit CpuSelfVoronoiBackend(int threads) : threads_(resolve_threads(threads)) {}

  std::string name() const override { return "cpu"; }
  std::string device() const override { return ""; }
  double distance_error_bound(double extent) const override {
    return kCpuSelfErrorBoundUnits * 0x1p-24 * extent;
  }

  SelfDvdOutput compute(const SelfDvdInput& self) override {
    validate_self_dvd_input(self);
    Stopwatch watch;
    const DvdInput& in = self.dvd;
    const std::size_t tri_count = in.tri_site.size();
    const std::size_t sample_count = in.voxels.size();

    std::vector<PreparedTriangle> prepared(tri_count);
    std::vector<Vec3> box_lo(tri_count), box_hi(tri_count);
    std::vector<std::array<std::int32_t, 3>> first_bin(tri_count);
    parallel_for(tri_count, threads_, [&](std::size_t t) {
      const double* c = &in.tri_xyz_d[9 * t];
      const Triangle tri{Vec3(c[0], c[1], c[2]), Vec3(c[3], c[4], c[5]), Vec3(c[6], c[7], c[8])};
      prepared[t] = prepare_triangle(tri);
      box_lo[t] = tri[0].cwiseMin(tri[1]).cwiseMin(tri[2]);
      box_hi[t] = tri[0].cwiseMax(tri[1]).cwiseMax(tri[2]);
      first_bin[t] = bins_overlapping(in, box_lo[t], box_hi[t]).lo;
    });

    // Runs of equal voxels: [starts[r], starts[r + 1]).
    std::vector<std::size_t> starts;
    for (std::size_t k = 0; k < sample_count; ++k)
      if (k == 0 || in.voxels[k] != in.voxels[k - 1]) starts.push_back(k);
    starts.push_back(sample_count);

    const VoronoiGrid& grid = in.grid;
    const double slack = kPrefilterSlack * grid.cell *
                         static_cast<double>(grid.dims[0] + grid.dims[1] + grid.dims[2]);
    SelfDvdOutput out;
    out.dist.resize(sample_count);
    parallel_for(starts.size() - 1, threads_, [&](std::size_t r) {
      const std::size_t first = starts[r], last = starts[r + 1];
      const std::int64_t id = in.voxels[first];
      const std::int64_t x = id % grid.dims[0];
      const std::int64_t y = (id / grid.dims[0]) % grid.dims[1];
      const std::int64_t z = id / (std::int64_t{grid.dims[0]} * grid.dims[1]);
      const Vec3 q = grid.cell * Vec3(static_cast<double>(x) + 0.5, static_cast<double>(y) + 0.5,
                                      static_cast<double>(z) + 0.5);
      // Per sample of this voxel: its triangle's object and vertices, band, best so far.
      struct Slot {
        std::int32_t site;
        std::array<std::int32_t, 3> v;
        double band;
        double best;
      };
      std::vector<Slot> slots;
      double max_band = 0;
      for (std::size_t k = first; k < last; ++k) {
        const auto f = static_cast<std::size_t>(self.sample_triangle[k]);
        slots.push_back({in.tri_site[f],
                         {self.tri_vertices[3 * f], self.tri_vertices[3 * f + 1], self.tri_vertices[3 * f + 2]},
                         in.band[k], kInfinity});
        max_band = std::max(max_band, static_cast<double>(in.band[k]));
      }
      // A triangle can matter only while some slot could still take it.
      auto cutoff = [&] {
        double c = 0;
        for (const Slot& s : slots) c = std::max(c, std::min(s.band, s.best));
        return c + slack;
      };
      double cut = cutoff();
      const BinRange range = bins_within(in, q, max_band);
      for (std::int32_t bz = range.lo[2]; bz <= range.hi[2]; ++bz)
        for (std::int32_t by = range.lo[1]; by <= range.hi[1]; ++by)
          for (std::int32_t bx = range.lo[0]; bx <= range.hi[0]; ++bx) {
            const auto b = static_cast<std::size_t>(bin_id(in, bx, by, bz));
            const std::array<std::int32_t, 3> here{bx, by, bz};
            for (std::int32_t i = in.bin_offsets[b]; i < in.bin_offsets[b + 1]; ++i) {
              const auto t = static_cast<std::size_t>(in.bin_tris[static_cast<std::size_t>(i)]);
              // Visit a triangle once: in the first visited bin of its own range.
              bool first_visit = true;
              for (std::size_t a = 0; a < 3; ++a)
                first_visit = first_visit && std::max(first_bin[t][a], range.lo[a]) == here[a];
              if (!first_visit) continue;
              const double box_sq = (box_lo[t] - q).cwiseMax(q - box_hi[t]).cwiseMax(0.0).squaredNorm();
              if (box_sq > cut * cut) continue;
              const std::int32_t site = in.tri_site[t];
              const std::int32_t* tv = &self.tri_vertices[3 * t];
              double d = -1;  // computed on first use
              bool changed = false;
              for (Slot& s : slots) {
                if (s.site != site) continue;
                bool adjacent = false;
                for (int a = 0; a < 3; ++a)
                  for (int c = 0; c < 3; ++c) adjacent = adjacent || s.v[a] == tv[c];
                if (adjacent) continue;
                if (d < 0) d = std::sqrt(point_triangle_distance(q, prepared[t]).squared_distance);
                if (d < s.band && d < s.best) {
                  s.best = d;
                  changed = true;
                }
              }
              if (changed) cut = cutoff();
            }
          }
      for (std::size_t k = first; k < last; ++k) {
        const Slot& s = slots[k - first];
        out.dist[k] = s.best < s.band ? static_cast<float>(s.best) : in.band[k];
      }
    });
    out.compute_ms = watch.elapsed_ms();
    return out;
  }

 private:
  int threads_;
};

}  // namespace

std::unique_ptr<SelfVoronoiBackend> make_cpu_self_voronoi_backend(int threads) {
  return std::make_unique<CpuSelfVoronoiBackend>(threads);
}

}  // namespace vproxq
