#include "core/voronoi/ccd_stage2.hpp"

#include "core/parallel.hpp"
#include "core/timer.hpp"

#include <Eigen/Geometry>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <memory>
#include <stdexcept>

namespace vproxq {
namespace {

// ---------------------------------------------------------------------------------------------
// Conservativeness of the records (CcdVoxelRecord), including rounding.
//
// Grid: voxel X = (x, y, z) is the closed cube origin + cell * [X, X + 1] (exact reals; origin
// and cell are doubles). Scaled coordinates: u*(p) = (p - origin) / cell exactly. dims[k] =
// floor(fl(ext_k / cell) (1 + 1e-12)) + 1 exceeds the exact ext_k / cell (two roundings of
// relative 2^-53 each), so the cubes cover the scene's swept box, which holds every widened
// hull: every point q of a hull lies in the voxel clamp(floor(u*(q))), whose cube contains q.
//
// Claim: a record keeps every voxel whose cube meets H ⊕ [-μ, μ]^3, H the hull of the
// triangle's 6 exact corner positions at ta and tb (u*-space: corners u*_c(t) = u*_c(0) +
// t (u*_c(1) - u*_c(0)), with ta = s / K, tb = (s + 1) / K exact since K is a power of two),
// μ the culling margin. For an axis m (any nonzero integer vector) the cube's projection is
// [m.X - neg, m.X + pos] (pos, neg: sums of the positive and negative parts of m), the widened
// hull's is [L* - μ' |m|_1, U* + μ' |m|_1] with L*, U* the extremes of m.u* over the 6 corners
// and μ' = μ / cell. They are disjoint iff m.X + pos < L* - μ'|m|_1 or m.X - neg > U* +
// μ'|m|_1. The code computes L, U, μ' in double: u = fl(fl(p - origin) / cell) has error
// <= 2 * 2^-53 |u*|, the lerp fl(u0 + fl(t fl(u1 - u0))) adds <= 4 * 2^-53 * 2 Umax (Umax =
// max dims + 1 bounds every |u*| and |u|), the integer-weighted dot product (exact products of
// |m_k| <= 1024 by doubles, rounded, two sums) <= 3 * 2^-53 |m|_1 Umax on top of |m|_1 times
// the coordinate error: |L - L*|, |U - U*| <= 14 * 2^-53 |m|_1 Umax < 2e-15 |m|_1 Umax. The
// widening and the thresholds (a handful more operations on numbers below V = 2 |m|_1 (Umax +
// μ' + 1)) add < 1e-15 V. The code subtracts err = kSlackRel V with kSlackRel = 1e-10 (five
// orders of magnitude to spare) before rounding outwards to integers:
//   below = ceil(L - μ'|m|_1 - err - pos) - 1 < L* - μ'|m|_1 - pos,
//   above = floor(U + μ'|m|_1 + err + neg) + 1 > U* + μ'|m|_1 + neg,
// so "m.X <= below" or "m.X >= above" (what drops a voxel) implies disjointness. The box is
// the same with m = e_k, rounded with floor on both ends (a voxel meeting [lo, hi] only at
// lo = x + 1 need not be kept: the point there also lies in voxel x + 1 = floor(lo), kept).
// Clamping thresholds to ±2^26 changes nothing: |m.X| <= 3 * 1024 * 2^12 < 2^26 (dims are
// capped at kMaxDim). All integer work is exact in int32, hence identical on every backend.
// ---------------------------------------------------------------------------------------------
constexpr double kSlackRel = 1e-10;
constexpr std::int32_t kAxisScale = 1024;
constexpr std::int32_t kThresholdCap = 1 << 26;
constexpr std::int32_t kMaxDim = 4096;
constexpr std::size_t kChunk = 256;
/// Default cell: this many times the median size of a triangle's per-slot box. Smaller cells
/// cull more pairs but mark more voxels (cubically more); measured on blobs and cloth.
constexpr double kCellFactor = 0.5;
/// Upper bound on the estimated voxels visited per (triangle, slot) record, on average (the
/// 200-blob scene visits ~17 with the factor above; the bound only bites on mixed sizes).
constexpr double kRoomPerRecord = 80;
/// The same bound for a grid given by --ccd-grid: it honours the grid unless the records would
/// cover some thousands of voxels each (a small scene far from the origin, where the culling
/// margin dwarfs the triangles: at 1e12, a given grid of 128 took over 60 s and 19 GB, 200 ran
/// out of memory; near the origin, 4096 took 12.7 s and 5.2 GB on 200 triangles; then --grid
/// set this grid too). Finer than the default it costs far more than it saves
/// (docs/algorithms.md, "Continuous collision detection"), hence the option of its own.
constexpr double kRoomPerRecordGiven = 64 * kRoomPerRecord;

std::int64_t floor_div(std::int64_t a, std::int64_t b) {  // b > 0
  const std::int64_t q = a / b;
  return (a % b != 0 && a < 0) ? q - 1 : q;
}
std::int64_t ceil_div(std::int64_t a, std::int64_t b) { return -floor_div(-a, b); }

std::int32_t clamp_threshold(double v) {
  return static_cast<std::int32_t>(std::clamp(v, -static_cast<double>(kThresholdCap), static_cast<double>(kThresholdCap)));
}

/// The keys of one record, written from `out`, ascending; returns their number. Row by row:
/// the x range of each (y, z) row solved from the three half-spaces in exact integer
/// arithmetic (the same set as ccd_record_keys' voxel-by-voxel test).
std::uint32_t write_record_keys(const CcdVoxelRecord& r, const std::array<std::int32_t, 3>& dims,
                                std::uint32_t* out) {
  std::uint32_t n = 0;
  for (std::int32_t z = r.lo[2]; z <= r.hi[2]; ++z)
    for (std::int32_t y = r.lo[1]; y <= r.hi[1]; ++y) {
      std::int64_t xa = r.lo[0], xb = r.hi[0];
      for (int a = 0; a < 3 && xa <= xb; ++a) {
        const std::int64_t m0 = r.axis[a][0];
        const std::int64_t rest = std::int64_t{r.axis[a][1]} * y + std::int64_t{r.axis[a][2]} * z;
        const std::int64_t lo = std::int64_t{r.below[a]} - rest, hi = std::int64_t{r.above[a]} - rest;
        // Keep x with lo < m0 x < hi.
        if (m0 == 0) {
          if (!(lo < 0 && 0 < hi)) xb = xa - 1;
        } else if (m0 > 0) {
          xa = std::max(xa, floor_div(lo, m0) + 1);
          xb = std::min(xb, ceil_div(hi, m0) - 1);
        } else {
          xa = std::max(xa, floor_div(-hi, -m0) + 1);
          xb = std::min(xb, ceil_div(-lo, -m0) - 1);
        }
      }
      const std::uint32_t row = r.key_base + static_cast<std::uint32_t>(dims[0]) *
                                                 (static_cast<std::uint32_t>(y) + static_cast<std::uint32_t>(dims[1]) * static_cast<std::uint32_t>(z));
      for (std::int64_t x = xa; x <= xb; ++x) out[n++] = row + static_cast<std::uint32_t>(x);
    }
  return n;
}

class CpuCcdVoxelBackend final : public CcdVoxelBackend {
 public:
  explicit CpuCcdVoxelBackend(int threads) : threads_(std::max(1, threads)) {}
  std::string name() const override { return "cpu"; }
  CcdVoxelOutput voxelize(const CcdVoxelInput& in) override {
    Stopwatch sw;
    CcdVoxelOutput out;
    out.keys.resize(static_cast<size_t>(in.out_offsets.back()));
    out.counts.resize(in.records.size());
    const size_t chunks = (in.records.size() + kChunk - 1) / kChunk;
    std::unique_ptr<std::atomic<std::uint32_t>[]> table;
    if (in.cooccupancy) table.reset(new std::atomic<std::uint32_t>[in.key_count]());
    parallel_for(chunks, threads_, [&](size_t c) {
      const size_t end = std::min(in.records.size(), (c + 1) * kChunk);
      for (size_t r = c * kChunk; r < end; ++r) {
        std::uint32_t* keys = out.keys.data() + in.out_offsets[r];
        out.counts[r] = write_record_keys(in.records[r], in.dims, keys);
        if (!table) continue;
        // The table's final state does not depend on the order of the marks: a key ends at
        // object + 1 iff only that object marks it, at kCcdSharedKey iff two or more do.
        const std::uint32_t me = static_cast<std::uint32_t>(in.record_object[r]) + 1;
        for (std::uint32_t k = 0; k < out.counts[r]; ++k) {
          std::atomic<std::uint32_t>& e = table[keys[k]];
          std::uint32_t seen = 0;
          if (!e.compare_exchange_strong(seen, me, std::memory_order_relaxed) && seen != me)
            e.store(kCcdSharedKey, std::memory_order_relaxed);
        }
      }
    });
    if (table) {
      // After the marking pass (parallel_for joined its threads): read-only.
      out.foreign.assign(in.records.size(), 0);
      parallel_for(chunks, threads_, [&](size_t c) {
        const size_t end = std::min(in.records.size(), (c + 1) * kChunk);
        for (size_t r = c * kChunk; r < end; ++r) {
          const std::uint32_t* keys = out.keys.data() + in.out_offsets[r];
          for (std::uint32_t k = 0; k < out.counts[r]; ++k)
            if (table[keys[k]].load(std::memory_order_relaxed) == kCcdSharedKey) {
              out.foreign[r] = 1;
              break;
            }
        }
      });
    }
    out.compute_ms = sw.elapsed_ms();
    return out;
  }

 private:
  int threads_;
};

/// LSD radix sort of 32-bit keys (three passes of 11 bits): linear in the number of marks.
void radix_sort(std::vector<std::uint32_t>& v) {
  std::vector<std::uint32_t> tmp(v.size());
  for (int shift = 0; shift < 32; shift += 11) {
    std::array<std::size_t, 2049> count{};
    for (std::uint32_t k : v) ++count[((k >> shift) & 2047u) + 1];
    for (size_t b = 1; b < count.size(); ++b) count[b] += count[b - 1];
    for (std::uint32_t k : v) tmp[count[(k >> shift) & 2047u]++] = k;
    v.swap(tmp);
  }
}

}  // namespace

void ccd_record_keys(const CcdVoxelRecord& r, const std::array<std::int32_t, 3>& dims,
                     std::vector<std::uint32_t>& out) {
  for (std::int32_t z = r.lo[2]; z <= r.hi[2]; ++z)
    for (std::int32_t y = r.lo[1]; y <= r.hi[1]; ++y)
      for (std::int32_t x = r.lo[0]; x <= r.hi[0]; ++x) {
        bool keep = true;
        for (int a = 0; a < 3; ++a) {
          const std::int32_t d = r.axis[a][0] * x + r.axis[a][1] * y + r.axis[a][2] * z;
          keep = keep && r.below[a] < d && d < r.above[a];
        }
        if (keep)
          out.push_back(r.key_base + static_cast<std::uint32_t>(x) +
                        static_cast<std::uint32_t>(dims[0]) * (static_cast<std::uint32_t>(y) + static_cast<std::uint32_t>(dims[1]) * static_cast<std::uint32_t>(z)));
      }
}

std::unique_ptr<CcdVoxelBackend> make_cpu_ccd_voxel_backend(int threads) {
  return std::make_unique<CpuCcdVoxelBackend>(threads);
}

CcdVoxelCulling::CcdVoxelCulling(const Frame& from, const Frame& to, const CcdSweep& sweep,
                                 int grid_resolution, int threads)
    : CcdVoxelCulling(from, to, sweep, CcdVoxelOptions{grid_resolution, 0, threads},
                      *make_cpu_ccd_voxel_backend(threads)) {}

CcdVoxelCulling::CcdVoxelCulling(const Frame& from, const Frame& to, const CcdSweep& sweep,
                                 const CcdVoxelOptions& options, CcdVoxelBackend& backend,
                                 const CcdTriangleMask* only) {
  Stopwatch sw;
  const int threads = std::max(1, options.threads);
  slots_ = options.slots > 0 ? options.slots : CcdVoxelOptions::kDefaultSlots;
  if (slots_ < 1 || slots_ > 64 || (slots_ & (slots_ - 1)) != 0)
    throw std::invalid_argument("CCD Stage II: slots must be a power of two in [1, 64]");
  const size_t n = from.objects.size();
  first_.assign(n + 1, 0);
  std::vector<std::uint8_t> part(n, 0);
  for (Index i : sweep.participants.objects) part[static_cast<size_t>(i)] = 1;
  for (size_t i = 0; i < n; ++i) first_[i + 1] = first_[i] + (part[i] ? from.objects[i].num_triangles() : 0);
  const std::int64_t total_tris = first_[n];
  offsets_.assign(1, 0);
  // A triangle without records (left out by `only`) is never ruled out (keeps(), share_voxel()).
  foreign_.assign(static_cast<size_t>(total_tris), 1);
  record_of_.assign(static_cast<size_t>(total_tris), -1);
  // The voxelized triangles (global ids, ascending, so each object's are consecutive: object
  // i's are tris[qfirst[i] .. qfirst[i + 1])), and the scene box: every one's swept box
  // widened by the step's margin (the prisms below), and by its own share (its box in the
  // sweep). The grid covers them all.
  std::vector<std::int64_t> tris;
  std::vector<std::int64_t> qfirst(n + 1, 0);
  AABB scene;
  for (size_t i = 0; i < n; ++i) {
    qfirst[i] = static_cast<std::int64_t>(tris.size());
    if (!part[i] || sweep.objects[i].empty()) continue;
    const std::vector<std::uint8_t>* mask = only ? &(*only)[i] : nullptr;
    const Object& o = from.objects[i];
    for (Index t = 0; t < o.num_triangles(); ++t) {
      if (mask && !marked(mask, static_cast<size_t>(t))) continue;
      const std::int64_t g = first_[i] + t;
      record_of_[static_cast<size_t>(g)] = static_cast<std::int64_t>(tris.size());
      tris.push_back(g);
      const Face& f = o.topology->faces[static_cast<size_t>(t)];
      AABB box;
      for (Index v : f) box.extend(sweep.vertices[i][static_cast<size_t>(v)]);
      box.lo.array() -= sweep.margin;
      box.hi.array() += sweep.margin;
      box.extend(sweep.triangles[i][static_cast<size_t>(t)]);
      scene.extend(box);
    }
  }
  qfirst[n] = static_cast<std::int64_t>(tris.size());
  const std::int64_t used = static_cast<std::int64_t>(tris.size());
  voxelized_ = static_cast<std::uint64_t>(used);
  if (scene.empty() || used == 0) return;
  const Vec3 ext = scene.hi - scene.lo;
  const double longest = std::max(ext.maxCoeff(), 1e-300);
  const double K = slots_;

  // Triangle id -> (object, triangle).
  std::vector<Index> tri_object(static_cast<size_t>(total_tris));
  for (size_t i = 0; i < n; ++i)
    for (std::int64_t t = first_[i]; t < first_[i + 1]; ++t) tri_object[static_cast<size_t>(t)] = static_cast<Index>(i);
  auto corner = [&](std::int64_t t, int c, bool end) -> const Vec3& {
    const Index i = tri_object[static_cast<size_t>(t)];
    const Object& o = (end ? to : from).objects[static_cast<size_t>(i)];
    const Face& f = o.topology->faces[static_cast<size_t>(t - first_[static_cast<size_t>(i)])];
    return o.positions[static_cast<size_t>(f[static_cast<size_t>(c)])];
  };

  // Cell. By default about the size of a triangle's box over one slot (median over the
  // step): coarser cells cannot separate neighbours, finer ones multiply the marks.
  double cell;
  {
    std::vector<double> size(static_cast<size_t>(used));
    parallel_for((static_cast<size_t>(used) + kChunk - 1) / kChunk, threads, [&](size_t c) {
      const std::int64_t end = std::min<std::int64_t>(used, static_cast<std::int64_t>((c + 1) * kChunk));
      for (std::int64_t q = static_cast<std::int64_t>(c * kChunk); q < end; ++q) {
        const std::int64_t t = tris[static_cast<size_t>(q)];
        AABB b0, b1;
        Vec3 motion = Vec3::Zero();
        for (int k = 0; k < 3; ++k) {
          b0.extend(corner(t, k, false));
          b1.extend(corner(t, k, true));
          motion = motion.cwiseMax((corner(t, k, true) - corner(t, k, false)).cwiseAbs());
        }
        size[static_cast<size_t>(q)] = ((b0.hi - b0.lo).cwiseMax(b1.hi - b1.lo) + motion / K).maxCoeff();
      }
    });
    if (options.grid_resolution > 0) {
      cell = longest / options.grid_resolution;
    } else {
      auto mid = size.begin() + static_cast<std::ptrdiff_t>(size.size() / 2);
      std::nth_element(size.begin(), mid, size.end());
      cell = kCellFactor * *mid;
      if (!(cell > 0) || !std::isfinite(cell)) cell = longest / 32;
    }
    // Budget: a few large triangles (a static floor or funnel next to a fine cloth) would
    // otherwise cover millions of voxels each. Estimate the voxels the records will visit
    // (a cube of a triangle's per-slot size widened by the culling margin on both sides, plus
    // a cell either side) and coarsen the cell until they average at most kRoomPerRecord.
    // (The margin grows with the coordinates' magnitude: far from the origin it can exceed
    // the triangles themselves.)
    cell = std::max(cell, longest / (kMaxDim - 2));
    const double budget = options.grid_resolution > 0 ? kRoomPerRecordGiven : kRoomPerRecord;
    for (int attempt = 0; attempt < 64; ++attempt) {
      double room = 0;
      for (double d : size) room += std::pow(std::min((d + 2 * sweep.margin) / cell, double{kMaxDim}) + 2, 3);
      if (room <= budget * static_cast<double>(size.size())) break;
      cell *= 1.25;
    }
  }
  // Caps: dims <= kMaxDim (int32 arithmetic of the records) and 32-bit keys.
  cell = std::max(cell, longest / (kMaxDim - 2));
  auto set_dims = [&] {
    for (int k = 0; k < 3; ++k)
      grid_.dims[k] = static_cast<std::int32_t>(std::floor(ext[k] / cell * (1 + 1e-12))) + 1;
  };
  set_dims();
  while (static_cast<double>(grid_.voxel_count()) * K > 4294967295.0) {
    cell *= 1.25;
    set_dims();
  }
  grid_.cell = cell;
  grid_.origin = scene.lo;
  const double umax = std::max({grid_.dims[0], grid_.dims[1], grid_.dims[2]}) + 1.0;
  const double mu = sweep.margin / cell;

  // Records: one per (triangle, slot), in that order, so that a triangle's keys are the
  // concatenation of its records' (ascending: the slot is the most significant part).
  CcdVoxelInput in;
  in.dims = grid_.dims;
  const size_t nrec = static_cast<size_t>(used) * static_cast<size_t>(slots_);
  in.records.resize(nrec);
  std::vector<std::uint64_t> room(nrec);
  const std::uint32_t per_slot = static_cast<std::uint32_t>(grid_.voxel_count());
  parallel_for((static_cast<size_t>(used) + kChunk - 1) / kChunk, threads, [&](size_t c) {
    const std::int64_t end = std::min<std::int64_t>(used, static_cast<std::int64_t>((c + 1) * kChunk));
    for (std::int64_t q = static_cast<std::int64_t>(c * kChunk); q < end; ++q) {
      const std::int64_t t = tris[static_cast<size_t>(q)];
      std::array<Vec3, 3> u0, u1;
      for (int k = 0; k < 3; ++k) {
        u0[static_cast<size_t>(k)] = (corner(t, k, false) - grid_.origin) / cell;
        u1[static_cast<size_t>(k)] = (corner(t, k, true) - grid_.origin) / cell;
      }
      for (int s = 0; s < slots_; ++s) {
        const double ta = s / K, tb = (s + 1) / K, tm = (s + 0.5) / K;
        std::array<Vec3, 6> p;
        std::array<Vec3, 3> pm;
        for (size_t k = 0; k < 3; ++k) {
          const Vec3 d = u1[k] - u0[k];
          p[k] = u0[k] + ta * d;
          p[k + 3] = u0[k] + tb * d;
          pm[k] = u0[k] + tm * d;
        }
        CcdVoxelRecord& r = in.records[static_cast<size_t>(q) * static_cast<size_t>(slots_) + static_cast<size_t>(s)];
        r.key_base = static_cast<std::uint32_t>(s) * per_slot;
        r.pad[0] = r.pad[1] = 0;
        std::uint64_t volume = 1;
        for (int k = 0; k < 3; ++k) {
          double lo = kInfinity, hi = -kInfinity;
          for (const Vec3& q : p) {
            lo = std::min(lo, q[k]);
            hi = std::max(hi, q[k]);
          }
          const double err = kSlackRel * 2 * (umax + mu + 1);
          auto cell_of = [&](double x) {
            return static_cast<std::int32_t>(std::clamp(std::floor(x), 0.0, static_cast<double>(grid_.dims[k] - 1)));
          };
          r.lo[k] = cell_of(lo - mu - err);
          r.hi[k] = cell_of(hi + mu + err);
          volume *= static_cast<std::uint64_t>(r.hi[k] - r.lo[k] + 1);
        }
        // Axes: the triangle's normal at the slot's start, end and middle (any axis is valid).
        const std::array<Vec3, 3> normals{(p[1] - p[0]).cross(p[2] - p[0]), (p[4] - p[3]).cross(p[5] - p[3]),
                                          (pm[1] - pm[0]).cross(pm[2] - pm[0])};
        for (size_t a = 0; a < 3; ++a) {
          const Vec3& nv = normals[a];
          const double big = nv.cwiseAbs().maxCoeff();
          if (!(big > 0) || !std::isfinite(big)) {  // no axis: always passes
            r.axis[a] = {0, 0, 0};
            r.below[a] = -kThresholdCap;
            r.above[a] = kThresholdCap;
            continue;
          }
          std::int32_t m1 = 0, pos = 0, neg = 0;
          Vec3 m;
          for (int k = 0; k < 3; ++k) {
            r.axis[a][static_cast<size_t>(k)] = static_cast<std::int32_t>(std::lround(nv[k] / big * kAxisScale));
            const std::int32_t mk = r.axis[a][static_cast<size_t>(k)];
            m[k] = mk;
            m1 += std::abs(mk);
            (mk > 0 ? pos : neg) += std::abs(mk);
          }
          double lo = kInfinity, hi = -kInfinity;
          for (const Vec3& q : p) {
            const double d = m.dot(q);
            lo = std::min(lo, d);
            hi = std::max(hi, d);
          }
          const double widen = mu * m1 + kSlackRel * 2 * m1 * (umax + mu + 1);
          r.below[a] = clamp_threshold(std::ceil(lo - widen - pos) - 1);
          r.above[a] = clamp_threshold(std::floor(hi + widen + neg) + 1);
        }
        room[static_cast<size_t>(q) * static_cast<size_t>(slots_) + static_cast<size_t>(s)] = volume;
      }
    }
  });
  in.record_object.resize(nrec);
  for (size_t r = 0; r < nrec; ++r) in.record_object[r] = tri_object[static_cast<size_t>(tris[r / static_cast<size_t>(slots_)])];
  in.key_count = static_cast<std::uint32_t>(grid_.voxel_count() * slots_);
  in.cooccupancy = in.key_count <= kCcdMaxDenseKeys;
  in.out_offsets.assign(nrec + 1, 0);
  for (size_t r = 0; r < nrec; ++r) in.out_offsets[r + 1] = in.out_offsets[r] + room[r];
  timings_.setup_ms = sw.elapsed_ms();
  sw.restart();

  CcdVoxelOutput out = backend.voxelize(in);
  timings_.voxelize_ms = sw.elapsed_ms();
  sw.restart();

  // Per-record CSR of the keys, without the unused room.
  offsets_.assign(nrec + 1, 0);
  for (size_t r = 0; r < nrec; ++r) offsets_[r + 1] = offsets_[r] + out.counts[r];
  keys_.resize(static_cast<size_t>(offsets_.back()));
  boxes_.resize(nrec);
  parallel_for((nrec + kChunk - 1) / kChunk, threads, [&](size_t c) {
    const size_t end = std::min(nrec, (c + 1) * kChunk);
    for (size_t r = c * kChunk; r < end; ++r) {
      std::copy_n(out.keys.data() + in.out_offsets[r], out.counts[r], keys_.data() + offsets_[r]);
      const CcdVoxelRecord& rec = in.records[r];
      for (size_t k = 0; k < 3; ++k) {
        boxes_[r][k] = static_cast<std::int16_t>(rec.lo[k]);
        boxes_[r][k + 3] = static_cast<std::int16_t>(rec.hi[k]);
      }
    }
  });
  timings_.compact_ms = sw.elapsed_ms();
  sw.restart();

  for (std::int64_t t : tris) foreign_[static_cast<size_t>(t)] = 0;
  if (in.cooccupancy) {
    for (std::int64_t q = 0; q < used; ++q)
      for (int s = 0; s < slots_; ++s)
        foreign_[static_cast<size_t>(tris[static_cast<size_t>(q)])] |= out.foreign[static_cast<size_t>(q * slots_ + s)] != 0;
  } else {
    // Too many keys for a dense table: each object's distinct keys, all of them together
    // radix-sorted; a key listed twice is shared. The same answer as the table.
    std::vector<std::vector<std::uint32_t>> distinct(n);
    parallel_for(n, threads, [&](size_t i) {
      if (qfirst[i] == qfirst[i + 1]) return;
      auto& d = distinct[i];
      d.assign(keys_.begin() + static_cast<std::ptrdiff_t>(offsets_[static_cast<size_t>(qfirst[i] * slots_)]),
               keys_.begin() + static_cast<std::ptrdiff_t>(offsets_[static_cast<size_t>(qfirst[i + 1] * slots_)]));
      std::sort(d.begin(), d.end());
      d.erase(std::unique(d.begin(), d.end()), d.end());
    });
    std::vector<std::uint32_t> all;
    for (const auto& d : distinct) all.insert(all.end(), d.begin(), d.end());
    radix_sort(all);
    std::vector<std::uint32_t> shared;
    for (size_t k = 1; k < all.size(); ++k)
      if (all[k] == all[k - 1] && (shared.empty() || shared.back() != all[k])) shared.push_back(all[k]);
    parallel_for((static_cast<size_t>(used) + kChunk - 1) / kChunk, threads, [&](size_t c) {
      const std::int64_t end = std::min<std::int64_t>(used, static_cast<std::int64_t>((c + 1) * kChunk));
      for (std::int64_t q = static_cast<std::int64_t>(c * kChunk); q < end; ++q)
        for (std::uint64_t k = offsets_[static_cast<size_t>(q * slots_)]; k < offsets_[static_cast<size_t>((q + 1) * slots_)]; ++k)
          if (std::binary_search(shared.begin(), shared.end(), keys_[static_cast<size_t>(k)])) {
            foreign_[static_cast<size_t>(tris[static_cast<size_t>(q)])] = 1;
            break;
          }
    });
  }
  timings_.cooccupancy_ms = sw.elapsed_ms();
}

bool CcdVoxelCulling::share_voxel(Index i, Index f, Index j, Index g) const {
  const std::int64_t qa = record_of_[static_cast<size_t>(first_[static_cast<size_t>(i)] + f)];
  const std::int64_t qb = record_of_[static_cast<size_t>(first_[static_cast<size_t>(j)] + g)];
  if (qa < 0 || qb < 0) return true;  // not voxelized: nothing rules the pair out
  const size_t ra = static_cast<size_t>(qa * slots_);
  const size_t rb = static_cast<size_t>(qb * slots_);
  for (size_t s = 0; s < static_cast<size_t>(slots_); ++s) {
    const auto& ba = boxes_[ra + s];
    const auto& bb = boxes_[rb + s];
    if (ba[0] > bb[3] || bb[0] > ba[3] || ba[1] > bb[4] || bb[1] > ba[4] || ba[2] > bb[5] || bb[2] > ba[5]) continue;
    const std::uint32_t* a = keys_.data() + offsets_[ra + s];
    const std::uint32_t* ae = keys_.data() + offsets_[ra + s + 1];
    const std::uint32_t* b = keys_.data() + offsets_[rb + s];
    const std::uint32_t* be = keys_.data() + offsets_[rb + s + 1];
    while (a != ae && b != be) {
      if (*a == *b) return true;
      if (*a < *b)
        ++a;
      else
        ++b;
    }
  }
  return false;
}

std::vector<std::uint32_t> CcdVoxelCulling::keys(Index object, Index triangle) const {
  const std::int64_t q = record_of_[static_cast<size_t>(first_[static_cast<size_t>(object)] + triangle)];
  if (q < 0) return {};
  const size_t r = static_cast<size_t>(q * slots_);
  return {keys_.begin() + static_cast<std::ptrdiff_t>(offsets_[r]),
          keys_.begin() + static_cast<std::ptrdiff_t>(offsets_[r + static_cast<size_t>(slots_)])};
}

}  // namespace vproxq
