#include "gl/voronoi_backend.hpp"

#include "core/parallel.hpp"
#include "gl/dvd_gather_common.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/timer.hpp"
#include "core/voronoi/bins.hpp"
#include "core/voronoi/cpu_gather.hpp"

namespace vproxq::gl {

// ---------------------------------------------------------------------------------------------
// δ_precision of shaders/dvd2_gather.comp (float32_error_bound).
//
// Claim: a distance the shader reports below the band differs from the exact distance between
// the double sample point p and the double triangle T by at most 569 * 2^-24 * E + 2^-50,
// where every coordinate (relative to the grid origin) lies in [-E, E]. The code uses 1024.
//
// Model. GLSL 4.30 (4.7.1): + - * are correctly rounded but the rounding mode is undefined, so
// each has relative error < 1 ulp <= u := 2^-23 (not 2^-24); x / y has 2.5 ulp (2.5u) for
// |y| in [2^-126, 2^126]; sqrt is "inherited from 1/inversesqrt": (2 + 2.5) ulp = 4.5u;
// dot(x, y) of vec3 is 3 products and 2 sums: |fl(x.y) - x.y| <= 3u sum|x_i y_i| <= 3u|x||y|.
// Subnormals may be flushed to zero (handled at the end). `precise` keeps the compiler from
// re-associating; contracting a*b+c into one fma only removes roundings. First-order terms
// are kept; the O(u^2) ones are below 1e-4 of the total and are covered by the final margin.
// All vectors below are differences of points in [-E(1+2u), E(1+2u)]^3, so every length is
// at most D := 2 sqrt(3) E (1 + 2u); L <= D is the longest edge. "x*" is an exact quantity,
// "x" its computed value.
//
// 1. Input rounding. The host rounds corners to float (to nearest): <= sqrt(3) (u/2) E each.
//    The shader's sample point (v + 0.5) * float(cell) is off by <= (u/2 + u) per coordinate:
//    sqrt(3) 1.5u E. The distance is 1-Lipschitz in p, and in T under moving every corner by
//    <= r (Hausdorff distance <= r): at most 2 sqrt(3) u E = 3.5 u E. From here on p and T are
//    the float data and d = dist(p, T).
//
// 2. Output. d_out = sqrt(min_j fl(v_j.v_j)) over the candidate vectors v_j: the sum of three
//    squares has relative error 3u, sqrt 4.5u, so d_out is within (1.5u + 4.5u)|v| = 6uD of
//    min_j |v_j|. It remains to show  d - 22.2uD <= min_j |v_j| <= d + 74uD.
//
// 3. Edge k, segment S = [c, c + e*], w* = p - c. The code's t lies in [0, 1] (clamp), so
//    c + t e* is on S; v = fl(w - fl(t e)) is within 2u|w*| + 3u|e*| <= 5uD of p - (c + t e*).
//    Hence |v| >= dist(p, S) - 5uD. For the upper side, fl(w.e) is within (2u + 3u)|w*||e*| of
//    w*.e*, fl(e.e) within 5u of |e*|^2, the division 2.5u: the unclamped parameter is off by
//    <= (5u|w*| + 7.5u |w*.e*|/|e*|) / |e*| <= 12.5u|w*|/|e*|; clamp is 1-Lipschitz and the
//    distance along S is |e*|-Lipschitz in t, so |v| <= dist(p, S) + 12.5uD + 5uD.
//
// 4. The face. ab = fl(b - a) (longest edge by computed length, so |ac*| <= L(1 + 5u) and
//    tau in [-O(u), 1 + O(u)]), h1 = fl(ac - fl(tau ab)) = ac - tau ab + e1, |e1| <= 3uL;
//    mu = fl(h1.ab)/ll with |mu||ab| <= 14.5uL (h1.ab is only rounding: |h1.ab| <= 11.5uL|ab|);
//    h = h1 - mu ab + e2, |e2| <= u|h1|; tau2 = fl(tau + mu). Define the float-defined triangle
//    T' = (a, a + ab, a + tau2 ab + h). Its corners are within uL, and (tau2 - tau - mu)ab +
//    (ac - ac*) + e1 + e2 <= (1 + 1 + 3 + 1)uL = 6uL, of T's: |dist(p, T') - d| <= 6uL. The
//    plane of T' is spanned exactly by ab and h; the point the code evaluates,
//    y = a + t ab + lambda h, lies in it exactly, whatever the rounding of t and lambda. This is
//    what makes the frame robust: a cap's badly determined normal only tilts T' by <= 6uL at
//    its apex, instead of making the projection inaccurate (as a cross product normal would).
//    Lower side: computed barycentrics >= 0 imply exact ones >= -u|lambda tau2| resp.
//    >= -(u|1 - t| + 2u|lambda (1 - tau2)|): their negative parts sum to n <= 4.01u, so y is
//    within 2n diam(T') <= 8.1uL of T'. v = fl(fl(ap - fl(t ab)) - fl(lambda h)) is within
//    3u|ap*| + 3u|t||ab| + 2u|lambda||h| <= 8.1uD of p - y. So |v| >= d - 6uL - 8.1uL - 8.1uD
//    >= d - 22.2uD. With 3., every candidate is >= d - 22.2uD.
//
// 5. Upper side. Let x* be the point of T' nearest to p and d' = |p - x*| <= d + 6uL.
//    (a) x* on an edge of T': that edge is within 6uL of the matching edge of T, so by 3. that
//        edge's candidate is <= d' + 6uL + 17.5uD <= d + 29.5uD.
//    (b) x* inside T', at distance rho from its boundary (= from the nearest edge line), and
//        p - x* orthogonal to the plane. Edge route: some edge candidate <= sqrt(d'^2 + rho^2)
//        + 6uL + 17.5uD <= d' + rho + 23.5uD, and rho <= |h| (the height of T' over ab).
//        Face route: with t_p = ap*.ab/|ab|^2, lambda_p = ap*.h/|h|^2, as in 3.
//        |t - t_p||ab| <= 9.5uD and |lambda - lambda_p||h| <= 9.5uD. ab and h are not exactly
//        orthogonal: g = ab.h = (h1.ab - mu|ab|^2) + ab.e2, |g| <= |ab|(4u|h| + 154u^2 L); the
//        foot's exact coordinates (t*, lambda*) in [0, 1.0002] x [0, 1] differ from (t_p,
//        lambda_p) by lambda* g / |ab|^2 and t* g / |h|^2, i.e. in position by
//        <= 4u|h| + 4.01uL + 155u^2 L^2 / |h|. So Pi := |y - x*| <= 27.01uD + 155u^2 L^2/|h|.
//        The computed barycentrics are within 3.01u resp. 5.01u (lambda: exact) of y's, i.e.
//        within 5.01uL in distance to the edge lines (times the heights <= L), and y's are
//        within Pi of x*'s: if rho > Pi + 5.01uL the face candidate is computed and
//        |v| <= sqrt(d'^2 + Pi^2) + 8.1uD <= d' + Pi + 8.1uD; otherwise rho <= Pi + 5.01uL.
//        Both cases: min |v| <= d' + 23.5uD + 5.01uL + min(Pi, |h|)
//          <= d' + 55.52uD + min(155u^2 L^2 / |h|, |h|) <= d' + 55.52uD + sqrt(155) uL
//          <= d + 6uL + 67.97uD <= d + 74uD.
//
// 6. Sum: |d_out - d| <= 74uD + 6uD = 80uD for the float data; plus 1uD for flushed
//    subnormal dot products feeding a division (an absolute 2^-126 over a divisor > 2^-100
//    shifts t by < 2^-26 = u/8, twice), plus step 1:
//    81 * 2 sqrt(3) (1 + 2u) u E + 3.5 u E = 284.1 u E = 568.2 * 2^-24 E.
//    Absolute term: squared lengths <= 2^-100 are treated as 0 (edges, longest edge, height h):
//    each such case moves the result by <= 2^-50; flushed subnormal lengths and squares add
//    < 2^-60. The code returns 1024 * 2^-24 E + 2^-48: a margin of 1.8x for slips in the
//    bookkeeping, still negligible next to the cell diagonal in δ (~2^-7 E at grid 128).
// Cross-check (an off-tree experiment): a C++ float emulation of the shader's distance, run
// under all four IEEE rounding modes on 2e6 caps (height down to 1e-12 of the length, and
// flat), needles and slivers with the point on, near and above their planes, stays below
// 2.1uD of the double distance of the float data; a cross-product barycentric face test on
// the same cases is off by up to 3e5 uD. Step 5 is what the frame of the longest edge buys.
// The top-2 selection and the band cut-off only take minima of, and compare, such values, so
// dist1 and dist2 inherit the bound (an order statistic is 1-Lipschitz in the max norm).
// The bin search and the bounding-box prefilter never drop a triangle that could change the
// result (see the shader).
// ---------------------------------------------------------------------------------------------
double GlVoronoiBackend::float32_error_bound(double extent) {
  return kFloat32ErrorUnits * 0x1p-24 * extent + 0x1p-48;
}

namespace {

ComputeProgram compile(const Context& context, const GlVoronoiOptions& options, double& ms) {
  std::optional<ComputeProgram> program;
  ms = finish_timed_ms(context, [&] {
    program.emplace(ComputeProgram::from_embedded(
        context, "dvd2_gather", {{"LOCAL_SIZE", std::to_string(options.local_size)}}));
  });
  return std::move(*program);
}


}  // namespace

GlVoronoiBackend::GlVoronoiBackend(const Context& context, const GlVoronoiOptions& options)
    : context_(context), options_(options), program_(compile(context, options, compile_ms_)) {}

std::string GlVoronoiBackend::device() const { return context_.renderer(); }

double GlVoronoiBackend::distance_error_bound(double extent) const {
  return float32_error_bound(extent);
}

/// site1 of a sample whose loops the shader did not finish (dvd2_gather.comp).
constexpr std::int32_t kShaderIncomplete = -2;

DvdOutput GlVoronoiBackend::compute(const DvdInput& in) {
  validate_dvd_input(in);
  check_dvd_addressable(in, "GlVoronoiBackend");
  DvdOutput out;
  last_dispatch_count_ = 0;
  const std::size_t voxel_count = in.voxels.size();
  out.site1.resize(voxel_count);
  out.site2.resize(voxel_count);
  out.dist1.resize(voxel_count);
  out.dist2.resize(voxel_count);
  if (voxel_count == 0) return out;

  // One dispatch per batch, each with its own sample, exclusion and result buffers.
  struct Batch {
    std::size_t first, count;
    StorageBuffer samples, exclude, results;
  };
  std::vector<Batch> batches;
  std::optional<DvdSharedBuffers> shared;
  out.upload_ms = finish_timed_ms(context_, [&] {
    shared.emplace(DvdSharedBuffers::upload(context_, in));
    // Per sample (binding 8): the excluded site, and the ids of its triangles when they are
    // consecutive, which the shader passes over in one step per bin.
    const bool sorted = std::is_sorted(in.tri_site.begin(), in.tri_site.end());
    std::vector<std::int32_t> exclude;
    for (const auto& [first, count] : plan_batches(context_, program_, voxel_count, options_.max_groups_per_dispatch)) {
      exclude.assign(4 * count, 0);
      for (std::size_t k = 0; k < count; ++k) {
        const std::int32_t site = in.exclude_site.empty() ? kNoIndex : in.exclude_site[first + k];
        const SkippedTriangles run = site_triangles(in, sorted, site);
        exclude[4 * k] = site;
        exclude[4 * k + 1] = run.lo;
        exclude[4 * k + 2] = run.hi;
      }
      batches.push_back({first, count, StorageBuffer::from_vector(context_, pack_samples(in, first, count)),
                         StorageBuffer::from_vector(context_, exclude),
                         StorageBuffer(context_, 16 * count, GL_STREAM_READ)});
    }
  });

  set_dvd_uniforms(program_, in, float32_error_bound(dvd_input_extent(in)));
  program_.set_int("bin_dims_z", in.bin_dims[2]);  // for the walk's bin gaps
  shared->bind();
  out.compute_ms = dispatch_batches(context_, program_, batches, [](const Batch& batch) {
    batch.samples.bind(4);
    batch.results.bind(5);
    batch.exclude.bind(8);
  }, last_dispatch_count_);

  out.readback_ms = finish_timed_ms(context_, [&] {
    for (const Batch& batch : batches) {
      const std::vector<std::int32_t> results = batch.results.download_vector<std::int32_t>(4 * batch.count);
      for (std::size_t k = 0; k < batch.count; ++k) {
        const std::size_t o = batch.first + k;
        out.site1[o] = results[4 * k];
        out.site2[o] = results[4 * k + 1];
        std::memcpy(&out.dist1[o], &results[4 * k + 2], sizeof(float));
        std::memcpy(&out.dist2[o], &results[4 * k + 3], sizeof(float));
      }
    }
  });
  // Samples the shader could not finish (a driver's loop cap: dvd2_gather.comp) are computed
  // by the CPU twin, whose error bound is below this backend's.
  std::vector<std::size_t> redo;
  for (std::size_t k = 0; k < voxel_count; ++k)
    if (out.site1[k] == kShaderIncomplete) redo.push_back(k);
  last_redone_ = redo.size();
  if (!redo.empty()) {
    const DvdOutput cpu = make_cpu_voronoi_backend(resolve_threads(options_.cpu_threads))->compute(with_samples(in, redo));
    for (std::size_t j = 0; j < redo.size(); ++j) {
      out.site1[redo[j]] = cpu.site1[j];
      out.site2[redo[j]] = cpu.site2[j];
      out.dist1[redo[j]] = cpu.dist1[j];
      out.dist2[redo[j]] = cpu.dist2[j];
    }
  }
  return out;
}

}  // namespace vproxq::gl
