#pragma once
// Stage II backend interface: the 2nd-order discrete Voronoi diagram (DVD) evaluated at the
// grid points that lie on sites (paper 4.3, 5.2). The host side (core/voronoi/stage2.cpp)
// builds the input: the voxels touched by the sites' triangles and a binning of the triangles;
// a backend (CPU here, GL compute in gl/) fills in, for every such voxel centre, the two
// nearest distinct sites and their distances, capped at the voxel's band.
#include "core/types.hpp"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace vproxq {

/// A uniform grid of cubic voxels. Voxel (x, y, z) spans origin + cell * [x, x+1] x ...;
/// its sample point is its centre. Linear id = x + dims[0] * (y + dims[1] * z).
struct VoronoiGrid {
  Vec3 origin = Vec3::Zero();
  double cell = 1;
  std::array<std::int32_t, 3> dims{1, 1, 1};

  std::int64_t voxel_count() const { return std::int64_t{dims[0]} * dims[1] * dims[2]; }
  Vec3 center(std::int64_t id) const {
    const std::int64_t x = id % dims[0], y = (id / dims[0]) % dims[1], z = id / (std::int64_t{dims[0]} * dims[1]);
    return origin + cell * Vec3(static_cast<double>(x) + 0.5, static_cast<double>(y) + 0.5, static_cast<double>(z) + 0.5);
  }
};

/// What a backend gets. Coordinates are relative to grid.origin (so float32 keeps precision
/// where it matters: the magnitude is the grid extent, not the scene's absolute position);
/// Stage II also divides every length by a power of two near the extent (StageGrid::unit), so
/// that the magnitudes are about 1 at every scene scale. A backend needs neither: it takes the
/// numbers as they come, and its distances are in the same units.
struct DvdInput {
  VoronoiGrid grid;
  /// Triangles: 9 floats each (x0 y0 z0 x1 y1 z1 x2 y2 z2, relative to grid.origin), and the
  /// double version of the same numbers for the CPU backend.
  std::vector<float> tri_xyz;
  std::vector<double> tri_xyz_d;
  std::vector<std::int32_t> tri_site;  ///< site (object id) of each triangle
  /// Sample voxels: linear ids, sorted ascending, unique, and each one's band: distances
  /// larger than band[k] need not be exact (report any value >= band[k], e.g. band[k]).
  std::vector<std::int64_t> voxels;
  std::vector<float> band;
  /// Per sample voxel (same order), or empty for "none anywhere": a site whose triangles the
  /// backend ignores there, or -1. Stage II passes the voxel's only site when a single site
  /// touches it: that site's own distance (about 0) is never used, only the nearest *other*
  /// sites, and skipping its many nearby triangles is most of the backend's work.
  std::vector<std::int32_t> exclude_site;
  /// Triangle binning: bins of bin_size x bin_size x bin_size voxels, bin_dims per axis;
  /// bin b's triangles are bin_tris[bin_offsets[b] .. bin_offsets[b+1]). A triangle is listed
  /// in every bin its bounding box overlaps. To find every triangle within distance r of a
  /// point, visit all bins overlapping the point's box expanded by r. Each bin's list is in
  /// ascending triangle order (the CPU backends skip an excluded site's run by binary search).
  std::int32_t bin_size = 4;
  std::array<std::int32_t, 3> bin_dims{1, 1, 1};
  std::vector<std::int32_t> bin_offsets;  ///< size bin count + 1
  std::vector<std::int32_t> bin_tris;
};

/// What a backend returns: per sample voxel (same order as DvdInput::voxels), among the sites
/// other than its exclude_site, the nearest site and the nearest site different from it (only
/// the nearest where exclude_site is set: then site2 is kNoIndex and dist2 the band), with distances (kNoIndex / band when none
/// within the band). Ties between sites go to the smaller site id.
struct DvdOutput {
  std::vector<std::int32_t> site1, site2;
  std::vector<float> dist1, dist2;
  double upload_ms = 0, compute_ms = 0, readback_ms = 0;
};

class DiscreteVoronoiBackend {
 public:
  virtual ~DiscreteVoronoiBackend() = default;
  /// "cpu" or "gpu".
  virtual std::string name() const = 0;
  /// Renderer string for the output's settings.device ("" for the CPU).
  virtual std::string device() const = 0;
  /// Largest absolute error of a reported distance below the band, for coordinates (relative
  /// to the grid origin) of magnitude at most `extent`: δ_precision of Lemma 2.
  virtual double distance_error_bound(double extent) const = 0;
  virtual DvdOutput compute(const DvdInput& in) = 0;
};

/// The multi-threaded CPU twin (double precision). `threads` >= 1.
std::unique_ptr<DiscreteVoronoiBackend> make_cpu_voronoi_backend(int threads);

}  // namespace vproxq
