#include "core/voronoi/self_stage2.hpp"

#include "core/mesh/adjacency.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "core/voronoi/bins.hpp"
#include "core/voronoi/grid_setup.hpp"
#include "core/voronoi/radix_sort.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <stdexcept>

namespace vproxq {
namespace {

// Bands are capped at this many cells: a narrower band only weakens culling, never correctness
// (a capped value gives D_l = cap - δ, which then simply culls less). Self bands start from the
// 2-ring bound, which is about one edge length, so the cap rarely binds at the default grid.
constexpr double kMaxSelfBandCells = 3.0;
// Bins of this many voxels per side for the backends' triangle lookup (more on very fine
// grids: bin_size_for()): twice the band's cap, so that a sample's walk spans 2 or 3 bins per
// axis. Skirt's frames 10-12, self Stage II (setup + compute) per frame with bins of 4
// voxels and of 6: 6.7 -> 6.1 ms at the default grid, 130 -> 111 at --grid 256, 377 -> 290
// at 512 (gpu on llvmpipe at 256: 894 -> 600); cloth-ball and funnel 4.0 -> 3.5 and 3.3 -> 2.8
// ms, the 18,484-triangle cloth-funnel frame 11.2-11.9 either way.
constexpr auto kBinSize = static_cast<std::int32_t>(2 * kMaxSelfBandCells);

struct Sample {
  std::int64_t voxel;
  std::int32_t triangle;  // index into the DvdInput triangle arrays
};

// Valence sums up to which may_have_candidate() decides exactly (above it: assumed).
constexpr std::size_t kMaxExactRingSize = 192;

/// Whether face f of an object of n triangles may have a triangle sharing no vertex with it:
/// false only when every triangle uses one of f's vertices (the faces of a tetrahedron, say),
/// so that f has no answer and sampling it is wasted (a crowd of 20,000 tetrahedra spent 4.2 s
/// of an 8.1 s frame sampling them). Decided exactly while f's vertices are used by at most
/// kMaxExactRingSize triangles in all; beyond that, true (sampling is always allowed).
bool may_have_candidate(const Adjacency& adj, const Face& f, Index n) {
  std::size_t sum = 0;
  for (const Index v : f) sum += adj.vertex_triangles(v).size();
  if (sum < static_cast<std::size_t>(n)) return true;  // f and its 1-ring: at most `sum` triangles
  if (sum > kMaxExactRingSize) return true;
  Index seen[kMaxExactRingSize];
  std::size_t k = 0;
  for (const Index v : f)
    for (const Index t : adj.vertex_triangles(v)) seen[k++] = t;
  std::sort(seen, seen + k);
  return static_cast<Index>(std::unique(seen, seen + k) - seen) < n;
}

/// The default self grid's cell is at least this times the median triangle's box size.
constexpr double kSelfCellOverMedianSize = 0.7;

}  // namespace

int default_self_grid_resolution(std::int64_t triangles, double longest, double median_size) {
  // The self bounds cull only when δ (~0.9 cell) is below the distances between neighbouring
  // non-adjacent triangles, about half an edge length; for a surface of n triangles spanning
  // the grid an edge is ~ extent / sqrt(n / 2), so the cell must shrink like 1 / sqrt(n).
  // sqrt(n) cells along the longest axis (cell ~ 0.7 edge), clamped to [32, 512], keeps Stage
  // II's cost moderate; on the cloth-funnel frame finer grids cull a little more but cost more
  // than they save (docs/algorithms.md, "Intra-object distance"). Objects that do not span the grid (a
  // crowd of small ones) have edges far above extent / sqrt(n): there the cell is not made
  // smaller than 0.7 times the median triangle's box (its longest side), which sqrt(n) cells
  // about match for one surface spanning the grid. 2,000 blobs of 180 triangles: 27.7 samples
  // per triangle at 512 cells, self Stage II 7.7 s, and no exact test culled.
  const double g = std::sqrt(static_cast<double>(std::max<std::int64_t>(triangles, 1)));
  double res = g;
  if (longest > 0 && median_size > 0) res = std::min(res, longest / (kSelfCellOverMedianSize * median_size));
  return static_cast<int>(std::clamp(std::lround(res), 32L, 512L));
}

void validate_self_dvd_input(const SelfDvdInput& in) {
  validate_dvd_input(in.dvd);
  auto fail = [](const std::string& what) {
    throw std::invalid_argument("SelfVoronoiBackend::compute: " + what);
  };
  const std::size_t tris = in.dvd.tri_site.size();
  if (in.sample_triangle.size() != in.dvd.voxels.size()) fail("one triangle per sample needed");
  if (in.tri_vertices.size() != 3 * tris) fail("tri_vertices is not 3 ids per triangle");
  for (const std::int32_t t : in.sample_triangle)
    if (t < 0 || static_cast<std::size_t>(t) >= tris) fail("sample_triangle holds an invalid triangle");
}

SelfVoronoiBounds compute_self_voronoi_bounds(const Frame& frame, const FrameBoxes& boxes,
                                              const std::vector<std::vector<double>>& ring2_bound,
                                              SelfVoronoiBackend& backend, int grid_resolution,
                                              int threads, const std::vector<std::uint8_t>* skip) {
  Stopwatch sw;
  SelfVoronoiBounds out;
  const size_t n = frame.objects.size();
  out.triangle_upper = ring2_bound;
  out.triangle_lower.resize(n);
  std::int64_t total_tris = 0;
  AABB scene;
  // Objects with fewer than 2 triangles have no non-adjacent pair: nothing to sample; nor are
  // those the caller leaves out. The grid (its box, and the default resolution's triangle
  // count and median size) is that of every object of 2 or more triangles, left out or not, so
  // that it does not depend on which static objects' results the caller reuses: with them out
  // of the box, funnel's frames after the first got cells of 0.023 instead of 0.054 at
  // --grid 256: 505K samples (the first frame: 113K) and 250 ms of self Stage II per frame,
  // where at 0.054 no moving triangle's 2-ring bound exceeds 2δ (0.4 ms).
  auto gridded_object = [&](size_t i) { return frame.objects[i].num_triangles() >= 2; };
  auto sampled_object = [&](size_t i) { return gridded_object(i) && !marked(skip, i); };
  bool any_sampled = false;
  for (size_t i = 0; i < n; ++i) {
    out.triangle_lower[i].assign(static_cast<size_t>(frame.objects[i].num_triangles()), -kInfinity);
    any_sampled = any_sampled || sampled_object(i);
    if (!gridded_object(i)) continue;
    total_tris += frame.objects[i].num_triangles();
    scene.extend(boxes.objects[i]);
  }
  if (!any_sampled || scene.empty()) return out;

  int res = grid_resolution;
  if (res <= 0) {
    res = default_self_grid_resolution(total_tris, (scene.hi - scene.lo).maxCoeff(),
                                       median_triangle_side(boxes, gridded_object));
  }
  const StageGrid sg = StageGrid::over(scene, res);
  out.grid = sg.grid;
  out.delta_precision = sg.delta_precision(backend);
  out.delta = sg.delta(out.delta_precision);
  const double slack = rounding_slack(boxes.magnitude);
  const double band_cap = kMaxSelfBandCells * sg.grid.cell;

  SelfDvdInput in;
  in.dvd.grid = sg.backend_grid();
  // Triangles numbered in object order (global ids); the backend gets only those it needs,
  // renumbered, below.
  std::vector<std::int64_t> tri_base(n + 1, 0);
  for (size_t i = 0; i < n; ++i) tri_base[i + 1] = tri_base[i] + frame.objects[i].num_triangles();
  const auto tri_count = static_cast<size_t>(tri_base[n]);

  // Conservative voxelization: samples per object in parallel, then sorted by (voxel, triangle)
  // (triangles are numbered in object order, so the result does not depend on threads).
  // Only triangles whose 2-ring bound exceeds 2δ are sampled (kSelfSampleRing2OverDelta).
  // Below δ, SD~ + δ >= δ is never below the 2-ring bound, so Stage II cannot lower their D_u,
  // and their D_l would be at most the 2-ring bound + slack, about δ: on the report scenes'
  // frames 10-13 the Stage II culls went 17 -> 17 (skirt), 26 -> 26 (bowl), 11 -> 0 (funnel)
  // and 2 -> 0 (cloth-ball) while the samples went down by up to 68%. Between δ and 2δ, D_u
  // can gain only where SD~ < δ, and D_l stays below 2δ, which culls about as little: frames
  // 10-13 again, 2δ instead of δ: culls 1 -> 1 (skirt), 26 -> 20 (bowl), 0 -> 0 (cloth-ball,
  // funnel, breaking), intra-object exact tests within 1% (breaking +0.9%), samples 299K ->
  // 58K (skirt), 362K -> 118K (cloth-ball), 188K -> 46K (breaking); on the 200-object scene
  // 214K -> 1.4K and self Stage II 121 -> 10 ms per frame, 0 culls either way. Nor are
  // triangles that share a vertex with every other triangle of their object
  // (may_have_candidate()): they have no answer and are no other triangle's candidate. An
  // unsampled triangle keeps D_u = 2-ring bound and D_l = -inf: less culling, never a
  // different answer.
  std::vector<std::vector<Sample>> hits(n);
  std::vector<std::uint64_t> sampled(n, 0);
  parallel_for(n, threads, [&](size_t i) {
    const Object& o = frame.objects[i];
    if (!sampled_object(i)) return;
    const Adjacency& adj = adjacency(*o.topology);
    for (Index t = 0; t < o.num_triangles(); ++t) {
      if (!(ring2_bound[i][static_cast<size_t>(t)] > kSelfSampleRing2OverDelta * out.delta)) continue;
      if (!may_have_candidate(adj, o.topology->faces[static_cast<size_t>(t)], o.num_triangles())) continue;
      ++sampled[i];
      const auto global = static_cast<std::int32_t>(tri_base[i] + t);
      sg.voxelize(o.triangle(t), boxes.triangles[i][static_cast<size_t>(t)],
                  [&](std::int64_t id) { hits[i].push_back({id, global}); });
    }
  });
  std::vector<Sample> samples;
  for (size_t i = 0; i < n; ++i) {
    samples.insert(samples.end(), hits[i].begin(), hits[i].end());
    out.sampled_triangles += sampled[i];
  }
  hits.clear();
  // Samples are in triangle order (objects in order, each object's triangles ascending): a
  // stable sort by voxel orders them by (voxel, triangle).
  stable_radix_sort(samples, [](const Sample& s) { return static_cast<std::uint64_t>(s.voxel); });

  // Bands: f needs exact values up to its 2-ring bound + δ (+ slack): below that a value can
  // improve D_u(f), and a capped value then gives D_l(f) = band - δ >= the 2-ring bound, which
  // culls f from every search whose bound is below its own. Capped at kMaxSelfBandCells cells.
  std::vector<float> tri_band(tri_count);
  for (size_t i = 0; i < n; ++i)
    for (size_t t = 0; t < ring2_bound[i].size(); ++t) {
      // As a float in backend units, rounded up: never below the double band.
      tri_band[static_cast<size_t>(tri_base[i]) + t] =
          sg.backend_band(std::min(ring2_bound[i][t] + out.delta + slack, band_cap));
    }
  in.dvd.voxels.reserve(samples.size());
  in.dvd.band.reserve(samples.size());
  in.sample_triangle.reserve(samples.size());
  for (size_t k = 0; k < samples.size(); ++k) {
    in.dvd.voxels.push_back(samples[k].voxel);
    in.dvd.band.push_back(tri_band[static_cast<size_t>(samples[k].triangle)]);
    in.sample_triangle.push_back(samples[k].triangle);
    if (k == 0 || samples[k].voxel != samples[k - 1].voxel) ++out.sample_voxels;
  }
  out.samples = samples.size();
  if (samples.empty()) {  // no triangle can gain: D_u and D_l stay as they are
    out.setup_ms = sw.elapsed_ms();
    return out;
  }
  // The backend's triangles: those of objects with samples that some sample's walk can reach
  // (reachable_triangles(): it reports only triangles within a sample's band, of the sample's
  // own object), and every sampled triangle. On the benchmark scenes a few hundred triangles
  // are sampled, and preparing all of them cost more than the samples did (skirt: 144 of
  // 12,288 sampled, 13-18 ms per frame).
  std::vector<std::uint8_t> is_sample(tri_count, 0);
  for (const Sample& smp : samples) is_sample[static_cast<size_t>(smp.triangle)] = 1;
  set_bin_layout(in.dvd, bin_size_for(in.dvd.grid, kBinSize));
  const std::vector<std::vector<Index>> kept = reachable_triangles(
      in.dvd, sg, boxes, threads, [&](size_t i) { return sampled[i] > 0; },
      [&](size_t i, Index t) { return is_sample[static_cast<size_t>(tri_base[i] + t)] != 0; });
  fill_dvd_triangles(in.dvd, frame, sg, kept);
  out.backend_triangles = in.dvd.tri_site.size();
  std::vector<std::int32_t> local(tri_count, -1);  // global id -> input triangle
  in.tri_vertices.reserve(3 * in.dvd.tri_site.size());
  for (size_t i = 0, next = 0; i < n; ++i) {
    const auto& faces = frame.objects[i].topology->faces;
    for (const Index t : kept[i]) {
      local[static_cast<size_t>(tri_base[i] + t)] = static_cast<std::int32_t>(next++);
      for (size_t c = 0; c < 3; ++c) in.tri_vertices.push_back(faces[static_cast<size_t>(t)][c]);
    }
  }
  for (std::int32_t& f : in.sample_triangle) f = local[static_cast<size_t>(f)];
  bin_triangles(in.dvd, in.dvd.bin_size);
  out.setup_ms = sw.elapsed_ms();

  const SelfDvdOutput dvd = backend.compute(in);
  out.upload_ms = dvd.upload_ms;
  out.compute_ms = dvd.compute_ms;
  out.readback_ms = dvd.readback_ms;

  // Scan: SD~(f) over f's samples, back in scene units (exact: sg.unit is a power of two). For
  // D_l a value at or past the band only says "at least band"; for D_u only values below the
  // band are distances to an actual triangle.
  sw.restart();
  std::vector<double> sd_lower(tri_count, kInfinity), sd_upper(tri_count, kInfinity);
  for (size_t k = 0; k < samples.size(); ++k) {
    const auto t = static_cast<size_t>(samples[k].triangle);
    const double v = sg.unit * dvd.dist[k], band = sg.unit * in.dvd.band[k];
    sd_lower[t] = std::min(sd_lower[t], std::min(v, band));
    if (v < band) sd_upper[t] = std::min(sd_upper[t], v);
  }
  for (size_t i = 0; i < n; ++i)
    for (size_t t = 0; t < out.triangle_lower[i].size(); ++t) {
      const size_t g = static_cast<size_t>(tri_base[i]) + t;
      // A sampled triangle marks at least one voxel; an unsampled one stays uncullable.
      if (sd_lower[g] != kInfinity) out.triangle_lower[i][t] = sd_lower[g] - out.delta;
      out.triangle_upper[i][t] = std::min(out.triangle_upper[i][t], sd_upper[g] + out.delta);
    }
  out.scan_ms = sw.elapsed_ms();
  return out;
}

}  // namespace vproxq
