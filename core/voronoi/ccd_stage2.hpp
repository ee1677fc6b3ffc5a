#pragma once
// Stage II for CCD (paper 3.2, 5.3): a conservative space-time voxelization of the swept
// triangles. The step [0, 1] is split into `slots` equal time slots; over slot [ta, tb] a
// moving triangle stays in the convex hull H of its 6 positions at ta and tb (each of its
// points at time t is a convex combination of its corners at t, and each corner at t of the
// corner at ta and at tb). A (slot, voxel) key is marked for a triangle unless a separating
// axis proves that the voxel misses H widened by the step's culling margin. If the kernel can
// report a primitive pair, the two primitives come within the margin (per axis) at one time t
// (core/geometry/ccd.hpp), so the voxel holding the first one's point at t is marked, for t's
// slot, by both owner triangles (see ccd.cpp for owners):
//  - every candidate triangle pair (inter- and intra-object) must share a marked key;
//  - inter-object: a triangle none of whose keys is marked by another object is dropped.
// Time slots matter for large motion: two triangles whose swept prisms overlap but that pass
// the same place at different times (the front and the back of a moving object) share no key.
//
// Exactness. The host turns each (triangle, slot) into a CcdVoxelRecord of integers: a voxel
// box and three integer separating axes with integer thresholds, rounded outwards with a
// derived error bound (ccd_stage2.cpp). Which voxels a record marks is then decided by exact
// int32 arithmetic, so the CPU backend here and the GL compute backend (gl/ccd_voxel_backend)
// produce identical key lists and identical culling.
#include "core/query/ccd.hpp"
#include "core/voronoi/discrete_voronoi.hpp"

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace vproxq {

/// One (triangle, time slot): voxel (x, y, z) in [lo, hi] (inclusive) is marked with key
/// key_base + x + dims[0] * (y + dims[1] * z) iff below[a] < axis[a] . (x, y, z) < above[a] for
/// a = 0, 1, 2. All |axis[a][k]| <= 1024 and |thresholds| <= 2^26 (no int32 overflow).
struct CcdVoxelRecord {
  std::array<std::int32_t, 3> lo, hi;
  std::array<std::array<std::int32_t, 3>, 3> axis;
  std::array<std::int32_t, 3> below, above;
  std::uint32_t key_base;  ///< slot * voxels per slot
  std::int32_t pad[2];     ///< 24 int32 in all (the GL backend uploads the array as is)
};
static_assert(sizeof(CcdVoxelRecord) == 24 * sizeof(std::int32_t), "record layout");

/// What a backend gets.
struct CcdVoxelInput {
  std::array<std::int32_t, 3> dims{1, 1, 1};
  std::vector<CcdVoxelRecord> records;
  /// Size records + 1: record r writes its keys (ascending) from out_offsets[r]; the room is
  /// its box's voxel count, so the keys of a record are never more than that.
  std::vector<std::uint64_t> out_offsets;
  /// Object id of each record's triangle.
  std::vector<std::int32_t> record_object;
  /// Keys range over [0, key_count). When `cooccupancy` is set the backend also finds, per
  /// record, whether one of its keys is marked by another object (a dense table of key_count
  /// entries: 0 = unmarked, object + 1 = marked by that object only, kCcdSharedKey = by two or
  /// more). The caller sets it only for tables of at most kCcdMaxDenseKeys entries.
  std::uint32_t key_count = 0;
  bool cooccupancy = false;
};

inline constexpr std::uint32_t kCcdSharedKey = 0xFFFFFFFFu;
inline constexpr std::uint32_t kCcdMaxDenseKeys = 1u << 24;

/// What a backend returns: keys (size out_offsets.back(); only the first counts[r] of each
/// record's room are meaningful) and the number of keys of each record.
struct CcdVoxelOutput {
  std::vector<std::uint32_t> keys;
  std::vector<std::uint32_t> counts;
  /// With in.cooccupancy: per record, 1 when one of its keys is marked by another object.
  std::vector<std::uint32_t> foreign;
  double upload_ms = 0, compute_ms = 0, readback_ms = 0;
};

class CcdVoxelBackend {
 public:
  virtual ~CcdVoxelBackend() = default;
  virtual std::string name() const = 0;  ///< "cpu" or "gpu"
  /// Marks every record's voxels; exact integer work (identical output for every backend).
  virtual CcdVoxelOutput voxelize(const CcdVoxelInput& in) = 0;
};

/// The CPU backend (`threads` >= 1).
std::unique_ptr<CcdVoxelBackend> make_cpu_ccd_voxel_backend(int threads);

/// The keys of one record, ascending, appended to `out`: the reference semantics that every
/// backend must match (the CPU backend runs it).
void ccd_record_keys(const CcdVoxelRecord& r, const std::array<std::int32_t, 3>& dims,
                     std::vector<std::uint32_t>& out);

struct CcdVoxelOptions {
  /// Cells along the longest axis of the scene's swept box; 0: chosen from the swept
  /// triangles (a cell about the size of a triangle's per-slot box, see ccd_stage2.cpp).
  int grid_resolution = 0;
  int slots = 0;  ///< time slots, a power of two; 0: kDefaultSlots
  int threads = 1;
  static constexpr int kDefaultSlots = 4;
};

/// Time spent in each part of Stage II (milliseconds).
struct CcdVoxelTimings {
  double setup_ms = 0;       ///< grid and records (host, double precision)
  double voxelize_ms = 0;    ///< the backend (for the GL one: upload + compute + readback)
  double compact_ms = 0;     ///< per-triangle key lists
  double cooccupancy_ms = 0;  ///< keys marked by two objects, per-triangle inter-object flags
};

/// Per object, per triangle: 1 to take part (objects or triangles past the end: 0).
using CcdTriangleMask = std::vector<std::vector<std::uint8_t>>;

class CcdVoxelCulling {
 public:
  /// Voxelizes the participating triangles of the step with `backend`: all of them, or with
  /// `only` those it marks. A triangle left out has no keys and is never ruled out (keeps()
  /// and share_voxel() are true for it), so the culling stays valid for every pair; leaving
  /// out triangles that take part in no candidate pair only saves work. The grid covers the
  /// voxelized triangles, and its default cell follows their sizes.
  CcdVoxelCulling(const Frame& from, const Frame& to, const CcdSweep& sweep,
                  const CcdVoxelOptions& options, CcdVoxelBackend& backend,
                  const CcdTriangleMask* only = nullptr);
  /// The same with the CPU backend, default slots.
  CcdVoxelCulling(const Frame& from, const Frame& to, const CcdSweep& sweep, int grid_resolution,
                  int threads);

  /// False when no key of triangle t of object i is marked by another object: t cannot take
  /// part in an inter-object collision.
  bool keeps(Index object, Index triangle) const {
    return foreign_[static_cast<size_t>(first_[static_cast<size_t>(object)] + triangle)] != 0;
  }
  /// True when the two triangles have a marked key (slot and voxel) in common.
  bool share_voxel(Index i, Index f, Index j, Index g) const;

  /// The sorted keys of triangle t of object i (for tests).
  std::vector<std::uint32_t> keys(Index object, Index triangle) const;

  const VoronoiGrid& grid() const { return grid_; }
  int slots() const { return slots_; }
  std::uint64_t marked_voxels() const { return keys_.size(); }  ///< (triangle, key) marks
  std::uint64_t voxelized_triangles() const { return voxelized_; }
  const CcdVoxelTimings& timings() const { return timings_; }

 private:
  VoronoiGrid grid_;
  int slots_ = 1;
  CcdVoxelTimings timings_;
  /// Triangles of all objects numbered consecutively: object i's start at first_[i].
  std::vector<std::int64_t> first_;
  /// Per triangle (numbered as above): its index among the voxelized triangles, whose records
  /// are q * slots .. q * slots + slots - 1; -1 when it was left out.
  std::vector<std::int64_t> record_of_;
  std::uint64_t voxelized_ = 0;
  /// CSR per record (triangle-major, then slot): keys_[offsets_[r] .. offsets_[r + 1]),
  /// ascending; a triangle's records are consecutive, so its keys are too.
  std::vector<std::uint64_t> offsets_;
  std::vector<std::uint32_t> keys_;
  /// Per record its voxel box (lo xyz, hi xyz): pairs whose boxes miss each other in a slot
  /// skip that slot's merge.
  std::vector<std::array<std::int16_t, 6>> boxes_;
  std::vector<std::uint8_t> foreign_;
};

}  // namespace vproxq
