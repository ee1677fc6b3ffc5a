#pragma once
// Stage II for CCD (paper 3.2, 5.3): a conservative voxelization of the swept triangles. The
// swept volume of a triangle over a step (its "bounding prism") lies in the convex hull H of
// its 6 positions (3 corners at frame k, 3 at frame k+1): every point of the moving triangle
// at time t is a convex combination of them. A voxel is marked for a triangle unless a
// separating axis proves that the voxel misses H widened by the step's culling margin. Two
// primitives can only collide (or be reported by the kernel within its tolerance) if the
// swept prisms of their triangles come within the margin, so some voxel is marked by both:
//  - inter-object: a triangle none of whose voxels is marked by another object is dropped;
//  - every candidate triangle pair must share a marked voxel.
// Grid conventions as Stage II of the distance query (stage2.cpp): cubic voxels, `--grid`
// cells along the longest axis of the scene's swept box, default_grid_resolution().
#include "core/query/ccd.hpp"
#include "core/voronoi/discrete_voronoi.hpp"

#include <cstdint>
#include <vector>

namespace vproxq {

class CcdVoxelCulling {
 public:
  /// Voxelizes every participating triangle of the step (`threads` workers).
  CcdVoxelCulling(const Frame& from, const Frame& to, const CcdSweep& sweep, int grid_resolution,
                  int threads);

  /// False when no voxel of triangle t of object i is marked by another object: t cannot
  /// take part in an inter-object collision.
  bool keeps(Index object, Index triangle) const {
    return foreign_[static_cast<size_t>(object)][static_cast<size_t>(triangle)] != 0;
  }
  /// True when the two triangles have a marked voxel in common.
  bool share_voxel(Index i, Index f, Index j, Index g) const;

  const VoronoiGrid& grid() const { return grid_; }
  std::uint64_t marked_voxels() const { return marks_; }  ///< (triangle, voxel) marks

 private:
  VoronoiGrid grid_;
  std::uint64_t marks_ = 0;
  /// Per object, CSR rows per triangle: the ids of its marked voxels, ascending.
  std::vector<std::vector<std::int64_t>> voxel_ids_;
  std::vector<std::vector<std::int32_t>> offsets_;
  std::vector<std::vector<std::uint8_t>> foreign_;
};

}  // namespace vproxq
