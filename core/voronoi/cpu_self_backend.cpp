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
#include "core/voronoi/cpu_gather.hpp"
#include "core/voronoi/self_stage2.hpp"

namespace vproxq {
namespace {

// distance_error_bound(), in units of extent * 2^-24: the derivation of the inter-object CPU
// backend (cpu_backend.cpp, kCpuErrorBoundUnits) applies unchanged: same double point–triangle
// distance, same final rounding to float; the 1-ring exclusion only removes candidates.
constexpr double kCpuSelfErrorBoundUnits = 8.0;

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
    const std::size_t sample_count = in.voxels.size();

    const GatherTriangles tris(in, threads_, /*entry_masks=*/true);

    // Runs of equal voxels: [starts[r], starts[r + 1]).
    std::vector<std::size_t> starts;
    for (std::size_t k = 0; k < sample_count; ++k)
      if (k == 0 || in.voxels[k] != in.voxels[k - 1]) starts.push_back(k);
    starts.push_back(sample_count);

    const double slack = cpu_prefilter_slack(in.grid);
    SelfDvdOutput out;
    out.dist.resize(sample_count);
    parallel_for(starts.size() - 1, threads_, [&](std::size_t r) {
      const std::size_t first = starts[r], last = starts[r + 1];
      const Vec3 q = voxel_centre(in.grid, in.voxels[first]);
      // Per sample of this voxel: its triangle's object and vertices, band, best so far.
      struct Slot {
        std::int32_t site;
        std::array<std::int32_t, 3> v;
        double band;
        double best;
      };
      // Reused from voxel to voxel: allocating it per voxel took about 7% of the self Stage II's
      // instructions on cloth-funnel frame 227.
      thread_local std::vector<Slot> slots;
      slots.clear();
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
      tris.for_each_in(in, bins_within(in, q, max_band), [&](std::size_t t) {
        if (tris.box_distance_squared(t, q) > cut * cut) return;
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
          if (d < 0) d = std::sqrt(point_triangle_distance(q, tris.prepared[t]).squared_distance);
          if (d < s.band && d < s.best) {
            s.best = d;
            changed = true;
          }
        }
        if (changed) cut = cutoff();
      });
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
