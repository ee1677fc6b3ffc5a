#pragma once
// Stage II for the intra-object query (paper 5.2.2): the discrete Voronoi diagram of each
// object's triangles, evaluated at the sample points of every triangle f while excluding f's
// 1-ring (the triangles sharing a vertex with f), and from it Lemma 2's bounds per triangle:
// D_u(f) >= SD(f) >= D_l(f), SD(f) being f's exact distance to its nearest non-adjacent triangle.
//
// Samples are (voxel, triangle f) pairs from the conservative voxelization (every voxel f
// touches). For each, a backend reports the distance from the voxel centre to the nearest
// triangle of f's object that shares no vertex with f, capped at the sample's band (the paper's
// GPU stores each feature's adjacency and discards adjacent features with a vector comparison;
// here each triangle carries its 3 vertex ids and the 1-ring test is a 3x3 id comparison).
#include "core/broad_phase/object_broad_phase.hpp"
#include "core/voronoi/discrete_voronoi.hpp"

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace vproxq {

/// What a self backend gets. `dvd` holds the grid, the triangles (tri_site = object id) and
/// their binning exactly as for the inter-object backends (bins.hpp), and one entry of
/// dvd.voxels / dvd.band per *sample*: samples are sorted by voxel, so the samples of one voxel
/// are consecutive (a voxel appears once per triangle touching it).
struct SelfDvdInput {
  DvdInput dvd;
  /// Sample k is on triangle sample_triangle[k] (an index into the triangle arrays).
  std::vector<std::int32_t> sample_triangle;
  /// 3 per triangle: its object-local vertex ids (triangles of different objects never
  /// compare: the object id is checked first).
  std::vector<std::int32_t> tri_vertices;
};

/// Per sample (same order as SelfDvdInput::dvd.voxels): the distance from the voxel centre to
/// the nearest triangle of the same object sharing no vertex with the sample's triangle, or
/// the band (or more) when there is none below the band.
struct SelfDvdOutput {
  std::vector<float> dist;
  double upload_ms = 0, compute_ms = 0, readback_ms = 0;
};

class SelfVoronoiBackend {
 public:
  virtual ~SelfVoronoiBackend() = default;
  /// "cpu" or "gpu".
  virtual std::string name() const = 0;
  /// Renderer string ("" for the CPU).
  virtual std::string device() const = 0;
  /// Largest absolute error of a reported distance below the band, for coordinates (relative
  /// to the grid origin) of magnitude at most `extent`: δ_precision of Lemma 2.
  virtual double distance_error_bound(double extent) const = 0;
  virtual SelfDvdOutput compute(const SelfDvdInput& in) = 0;
};

/// The multi-threaded CPU twin (double precision, results rounded to float). `threads` >= 1.
std::unique_ptr<SelfVoronoiBackend> make_cpu_self_voronoi_backend(int threads);

/// Checks what the self backends rely on, on top of validate_dvd_input(): one triangle per
/// sample, 3 vertex ids per triangle. Throws std::invalid_argument naming the problem.
void validate_self_dvd_input(const SelfDvdInput& in);

/// Only triangles whose 2-ring bound exceeds this many δ are sampled (self_stage2.cpp).
inline constexpr double kSelfSampleRing2OverDelta = 2.0;

struct SelfVoronoiBounds {
  VoronoiGrid grid;
  double delta = 0;            ///< δ = (cell diagonal)/2 + voxelization slack + δ_precision
  double delta_precision = 0;  ///< the backend's float error bound for this grid
  /// [object][triangle] D_u(f) = min(2-ring bound, SD~(f) + δ) over samples below their band.
  std::vector<std::vector<double>> triangle_upper;
  /// [object][triangle] D_l(f) = SD~(f) - δ (a capped sample counts as its band).
  std::vector<std::vector<double>> triangle_lower;
  std::uint64_t samples = 0;        ///< (voxel, triangle) pairs evaluated
  /// Triangles with samples: those whose 2-ring bound exceeds kSelfSampleRing2OverDelta δ and
  /// that have a non-adjacent triangle.
  std::uint64_t sampled_triangles = 0;
  std::uint64_t sample_voxels = 0;  ///< distinct voxels among the samples
  /// Triangles passed to the backend: the sampled ones and those of their objects that some
  /// sample's walk can reach (reachable_triangles()).
  std::uint64_t backend_triangles = 0;
  double setup_ms = 0, upload_ms = 0, compute_ms = 0, readback_ms = 0, scan_ms = 0;
};

/// Grid resolution for the self query when none is given (see self_stage2.cpp): sqrt(n)
/// cells along the longest axis (`longest`, of the box of the objects of 2 or more triangles,
/// left out or not), but cells no smaller than 0.7 times `median_size` (the median triangle
/// box's longest side), clamped to [32, 512].
int default_self_grid_resolution(std::int64_t triangles, double longest, double median_size);

/// Runs the self Stage II on a frame. `ring2_bound` is ring2_upper_bounds(frame) (query/
/// intra_distance.hpp): it sets each triangle's band, and a triangle whose 2-ring bound is at
/// most kSelfSampleRing2OverDelta δ is not sampled (it keeps D_u = its 2-ring bound and
/// D_l = -inf).
/// `grid_resolution` <= 0 picks default_self_grid_resolution(). Objects that `skip` marks (1)
/// are not sampled, but the grid covers them as it would without `skip` (it depends on the
/// frame alone); objects of fewer than 2 triangles are neither sampled nor in the grid.
SelfVoronoiBounds compute_self_voronoi_bounds(const Frame& frame, const FrameBoxes& boxes,
                                              const std::vector<std::vector<double>>& ring2_bound,
                                              SelfVoronoiBackend& backend, int grid_resolution,
                                              int threads, const std::vector<std::uint8_t>* skip = nullptr);

}  // namespace vproxq
