#pragma once
// Test support for CCD Stage II backends (core/voronoi/ccd_stage2.hpp): random records and a
// check of a backend's output against the voxel-by-voxel reference (CPU and GL tests).
#include <gtest/gtest.h>

#include "core/voronoi/ccd_stage2.hpp"
#include "support/random_scene.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <set>
#include <vector>

namespace vproxq::test {

/// Random records over `dims`: boxes inside the grid, axes with components in [-1024, 1024]
/// (some zero, some all zero), thresholds around the box's range so that all cases occur.
inline CcdVoxelInput random_ccd_voxel_input(std::uint64_t seed, std::array<std::int32_t, 3> dims, int slots, int records) {
  Rng rng(seed);
  CcdVoxelInput in;
  in.dims = dims;
  const std::uint32_t per_slot = static_cast<std::uint32_t>(dims[0] * dims[1] * dims[2]);
  in.key_count = per_slot * static_cast<std::uint32_t>(slots);
  in.cooccupancy = true;
  auto rint = [&](int lo, int hi) { return lo + static_cast<int>(std::floor(rng.uniform(0, 1) * (hi - lo + 1))) % (hi - lo + 1); };
  for (int r = 0; r < records; ++r) {
    CcdVoxelRecord rec{};
    for (int k = 0; k < 3; ++k) {
      const int a = rint(0, dims[k] - 1), b = rint(0, std::min(dims[k] - 1, a + 5));
      rec.lo[k] = std::min(a, b);
      rec.hi[k] = std::max(a, b);
    }
    for (int a = 0; a < 3; ++a) {
      const int kind = rint(0, 5);
      for (int k = 0; k < 3; ++k) rec.axis[a][k] = kind == 0 ? 0 : (rint(0, 3) == 0 ? 0 : rint(-1024, 1024));
      // The axis' range over the box corners, then thresholds cutting into it.
      int lo = 0, hi = 0;
      for (int k = 0; k < 3; ++k) {
        const int m = rec.axis[a][k];
        lo += std::min(m * rec.lo[k], m * rec.hi[k]);
        hi += std::max(m * rec.lo[k], m * rec.hi[k]);
      }
      rec.below[a] = rint(lo - 50, hi);
      rec.above[a] = rint(rec.below[a], hi + 50);
      if (kind == 0) {
        rec.below[a] = rint(-2, 1);
        rec.above[a] = rint(-1, 2);
      }
    }
    rec.key_base = static_cast<std::uint32_t>(rint(0, slots - 1)) * per_slot;
    in.records.push_back(rec);
    in.record_object.push_back(rint(0, 3));
  }
  in.out_offsets.assign(in.records.size() + 1, 0);
  for (size_t r = 0; r < in.records.size(); ++r) {
    const auto& rec = in.records[r];
    in.out_offsets[r + 1] = in.out_offsets[r] + std::uint64_t(rec.hi[0] - rec.lo[0] + 1) *
                                                    std::uint64_t(rec.hi[1] - rec.lo[1] + 1) *
                                                    std::uint64_t(rec.hi[2] - rec.lo[2] + 1);
  }
  return in;
}


/// Checks a backend's output against the voxel-by-voxel reference: keys, counts, and the
/// co-occupancy flags recomputed from the reference keys.
inline void expect_ccd_output_matches_reference(const CcdVoxelInput& in, const CcdVoxelOutput& out) {
  ASSERT_EQ(out.counts.size(), in.records.size());
  std::map<std::uint32_t, std::set<std::int32_t>> owners;
  std::vector<std::vector<std::uint32_t>> ref(in.records.size());
  for (size_t r = 0; r < in.records.size(); ++r) {
    ccd_record_keys(in.records[r], in.dims, ref[r]);
    for (std::uint32_t k : ref[r]) owners[k].insert(in.record_object[r]);
    ASSERT_EQ(out.counts[r], ref[r].size()) << "record " << r;
    const std::vector<std::uint32_t> got(out.keys.begin() + static_cast<std::ptrdiff_t>(in.out_offsets[r]),
                                         out.keys.begin() + static_cast<std::ptrdiff_t>(in.out_offsets[r] + out.counts[r]));
    ASSERT_EQ(got, ref[r]) << "record " << r;
  }
  if (!in.cooccupancy) return;
  ASSERT_EQ(out.foreign.size(), in.records.size());
  for (size_t r = 0; r < in.records.size(); ++r) {
    bool foreign = false;
    for (std::uint32_t k : ref[r]) foreign = foreign || owners[k].size() > 1;
    EXPECT_EQ(out.foreign[r] != 0, foreign) << "record " << r;
  }
}

}  // namespace vproxq::test
