// The CPU twin of the Stage II backend: the 2nd-order discrete Voronoi diagram at the sample
// voxels, in double precision, multi-threaded over voxels.
#include <algorithm>
#include <atomic>
#include <stdexcept>
#include <cmath>
#include <limits>

#include "core/geometry/point_triangle.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "core/voronoi/cpu_gather.hpp"
#include "core/voronoi/discrete_voronoi.hpp"

namespace vproxq {
namespace {

// distance_error_bound() of the CPU backend, in units of extent * 2^-24. The reported
// distances are float32 (DvdOutput), so the bound is dominated by that last rounding, not by
// the double arithmetic (a bound like 64 * 2^-53 * extent would be false):
//  - every coordinate lies in [-E, E] (E = extent), so every distance is at most
//    D = 2 sqrt(3) E; rounding the double distance to float (round to nearest) moves it by at
//    most 2^-24 * D = 3.47 units;
//  - the double distance (core/geometry/point_triangle) is exact up to a few 2^-53 * D for
//    every triangle shape (an accurate normal, and no face decision from doubtful signs; the
//    tests compare it with exactly known distances within 16 * 2^-53 of the coordinates'
//    magnitude, at most E here): negligible in units of 2^-24 * E. (Before 95967e3 it was not:
//    a point past the tip of a needle could come out far too close, e.g. 0.13 for a needle 2
//    long with a tip angle of 1e-12.)
//  - total <= 3.47 + (negligible 2^-53 terms) < 3.5 units; 8 leaves a wide margin.
constexpr double kCpuErrorBoundUnits = 8.0;

/// No site (internal): larger than every site id, so that the tie rule "smaller site id
/// first" needs no special case.
constexpr std::int32_t kNoSite = std::numeric_limits<std::int32_t>::max();

/// The two nearest distinct sites seen so far, ordered by (distance, site id).
struct TopTwo {
  double d1 = kInfinity, d2 = kInfinity;
  std::int32_t s1 = kNoSite, s2 = kNoSite;

  static bool before(double d, std::int32_t s, double d_other, std::int32_t s_other) {
    return d < d_other || (d == d_other && s < s_other);
  }

  /// Adds a triangle of site s at distance d. Keeping, per slot, the smallest distance seen
  /// for its site is enough: a site pushed out of slot 2 is behind two sites whose distances
  /// only decrease, so it can never come back with its (never smaller) old value.
  void add(double d, std::int32_t s) {
    if (s == s1) {
      d1 = std::min(d1, d);
    } else if (before(d, s, d1, s1)) {
      d2 = d1;  // also right when s == s2: its old, larger value is dropped
      s2 = s1;
      d1 = d;
      s1 = s;
    } else if (s == s2) {
      d2 = std::min(d2, d);
    } else if (before(d, s, d2, s2)) {
      d2 = d;
      s2 = s;
    }
  }
};

class CpuVoronoiBackend final : public DiscreteVoronoiBackend {
 public:
  explicit CpuVoronoiBackend(int threads) : threads_(resolve_threads(threads)) {}

  std::string name() const override { return "cpu"; }
  std::string device() const override { return ""; }

  double distance_error_bound(double extent) const override {
    return kCpuErrorBoundUnits * 0x1p-24 * extent;
  }

  DvdOutput compute(const DvdInput& in) override {
    validate_dvd_input(in);
    Stopwatch watch;
    const std::size_t voxel_count = in.voxels.size();

    const GatherTriangles tris(in, threads_);
    // Stamps for the walk's "seen" marks: unique over all calls (thread_local arrays outlive
    // a call on the calling thread), voxel index in the low 32 bits.
    static std::atomic<std::uint64_t> calls{0};
    const std::uint64_t call = (++calls) << 32;
    if (voxel_count >= (std::uint64_t{1} << 32))
      throw std::invalid_argument("CpuVoronoiBackend: more than 2^32 - 1 sample voxels");
    const double slack = cpu_prefilter_slack(in.grid);
    const bool sites_sorted = std::is_sorted(in.tri_site.begin(), in.tri_site.end());
    DvdOutput out;
    out.site1.resize(voxel_count);
    out.site2.resize(voxel_count);
    out.dist1.resize(voxel_count);
    out.dist2.resize(voxel_count);
    parallel_for(voxel_count, threads_, [&](std::size_t k) {
      const Vec3 q = voxel_centre(in.grid, in.voxels[k]);
      const double band = in.band[k];
      const std::int32_t skip = in.exclude_site.empty() ? kNoIndex : in.exclude_site[k];
      // With an excluded site only the nearest other site is asked for (DvdOutput).
      const bool nearest_only = skip != kNoIndex;
      TopTwo top;
      auto cutoff = [&] { return std::min(band, nearest_only ? top.d1 : top.d2) + slack; };
      thread_local std::vector<std::uint64_t> seen;
      for_each_nearest_first(in, q, bins_within(in, q, band), seen, call | k, cutoff, [&](std::size_t t) {
        if (in.tri_site[t] == skip) return;
        const double c = cutoff();
        if (tris.box_distance_squared(t, q) > c * c) return;
        const double d = std::sqrt(point_triangle_distance(q, tris.prepared[t]).squared_distance);
        if (d < band) top.add(d, in.tri_site[t]);
      }, site_triangles(in, sites_sorted, skip));
      const bool has2 = !nearest_only && top.s2 != kNoSite;
      out.site1[k] = top.s1 == kNoSite ? kNoIndex : top.s1;
      out.site2[k] = has2 ? top.s2 : kNoIndex;
      out.dist1[k] = top.s1 == kNoSite ? in.band[k] : static_cast<float>(top.d1);
      out.dist2[k] = has2 ? static_cast<float>(top.d2) : in.band[k];
    });
    out.compute_ms = watch.elapsed_ms();
    return out;
  }

 private:
  int threads_;
};

}  // namespace

std::unique_ptr<DiscreteVoronoiBackend> make_cpu_voronoi_backend(int threads) {
  return std::make_unique<CpuVoronoiBackend>(threads);
}

}  // namespace vproxq
