// Stage II contract (Lemma 2): D_u(O_i) bounds each object's exact separation distance from
// above, D_l(f) bounds each triangle's from below, and culling with them changes no answer.
#include "core/geometry/point_triangle.hpp"
#include "core/query/inter_distance.hpp"
#include "core/voronoi/grid_setup.hpp"
#include "core/voronoi/stage2.hpp"
#include "support/random_scene.hpp"
#include "support/self_meshes.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

namespace vproxq {
namespace {

/// Exact distance from triangle t of object i to every other object of the frame.
double exact_triangle_separation(const Frame& frame, size_t i, Index t) {
  double sd = kInfinity;
  for (size_t j = 0; j < frame.objects.size(); ++j) {
    if (j == i) continue;
    for (Index u = 0; u < frame.objects[j].num_triangles(); ++u)
      sd = std::min(sd, triangle_distance(frame.objects[i].triangle(t), frame.objects[j].triangle(u)).distance);
  }
  return sd;
}

/// A flat sheet of 2 * n * n triangles over [0, size]^2 at z = 0.
Object make_sheet(int n, double size, const std::string& name) {
  auto topo = std::make_shared<Topology>();
  Object o;
  o.name = name;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) o.positions.emplace_back(size * x / n, size * y / n, 0.0);
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const Index a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      topo->faces.push_back({a, b, d});
      topo->faces.push_back({a, d, c});
    }
  topo->num_vertices = static_cast<Index>(o.positions.size());
  o.topology = topo;
  return o;
}

/// The exact separation of every triangle from the other objects, [object][triangle].
std::vector<std::vector<double>> exact_separations(const Frame& frame) {
  std::vector<std::vector<double>> exact(frame.objects.size());
  for (size_t i = 0; i < frame.objects.size(); ++i)
    for (Index t = 0; t < frame.objects[i].num_triangles(); ++t) exact[i].push_back(exact_triangle_separation(frame, i, t));
  return exact;
}

/// Lemma 2's bounds against brute force (`exact`: exact_separations(), `ref`: the brute-force
/// inter-object distance), and Stage III with them gives brute force's answers.
void expect_bounds_and_answers(const Frame& frame, const FrameBoxes& boxes, const ObjectBroadPhase& stage1,
                               const VoronoiBounds& vb, const InterDistanceOutput& ref,
                               const std::vector<std::vector<double>>& exact) {
  for (size_t i = 0; i < frame.objects.size(); ++i) {
    EXPECT_GE(vb.object_upper[i], ref.per_object[i].distance) << "object " << i;
    for (size_t t = 0; t < exact[i].size(); ++t)
      ASSERT_LE(vb.triangle_lower[i][t], exact[i][t]) << "object " << i << " triangle " << t;
  }
  InterDistanceOptions opts{2, &vb};
  const auto got = inter_object_distance(frame, boxes, stage1, opts);
  for (size_t i = 0; i < frame.objects.size(); ++i) {
    EXPECT_EQ(got.per_object[i].nearest_object, ref.per_object[i].nearest_object);
    EXPECT_EQ(got.per_object[i].distance, ref.per_object[i].distance);
    EXPECT_EQ(got.per_object[i].triangles, ref.per_object[i].triangles);
    EXPECT_EQ(got.per_object[i].points[0], ref.per_object[i].points[0]);
  }
}

/// Stage II (CPU backend) on `frame` at each of `grids`: the bounds and answers against brute
/// force (expect_bounds_and_answers()), then check(bounds) for what the test adds.
template <typename Check>
void expect_bounds_at_grids(const Frame& frame, std::initializer_list<int> grids, const std::string& what,
                            const Check& check) {
  auto backend = make_cpu_voronoi_backend(2);
  const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
  const ObjectBroadPhase stage1 = object_broad_phase(frame, boxes, 2);
  const auto ref = inter_object_distance_brute_force(frame);
  const auto exact = exact_separations(frame);
  for (int grid : grids) {
    SCOPED_TRACE(what + " grid " + std::to_string(grid));
    const VoronoiBounds vb = compute_voronoi_bounds(frame, boxes, stage1, *backend, grid, 2);
    expect_bounds_and_answers(frame, boxes, stage1, vb, ref, exact);
    check(vb);
  }
}

TEST(Stage2, BoundsHoldAndResultsEqualBruteForce) {
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const Frame frame = test::make_random_frame(seed, 8, 1.5 + 0.5 * static_cast<double>(seed % 3), 1);
    expect_bounds_at_grids(frame, {8, 24, 64}, "seed " + std::to_string(seed),
                           [](const VoronoiBounds& vb) { EXPECT_GT(vb.delta, 0.0); });
  }
}

// An object without triangles (between two others) is never sampled and never a site; the
// others' bounds hold.
TEST(Stage2, AnObjectWithoutTrianglesIsLeftAlone) {
  test::Rng rng(3);
  Frame frame;
  frame.objects.push_back(test::make_blob(rng, Vec3(0, 0, 0), 0.5, 1, 0.1, "a"));
  Object empty;
  empty.name = "empty";
  empty.topology = std::make_shared<Topology>();
  frame.objects.push_back(std::move(empty));
  frame.objects.push_back(test::make_blob(rng, Vec3(1.1, 0.2, 0), 0.5, 1, 0.1, "b"));
  expect_bounds_at_grids(frame, {4, 16, 32}, "with an empty object", [](const VoronoiBounds& vb) {
    EXPECT_TRUE(vb.triangle_lower[1].empty());
    EXPECT_GT(vb.sample_voxels, 0u);
  });
}

// An object that Stage I proves to touch another (U_i = 0) is not sampled: no sample can lower
// its D_u, and its triangles near another object stay uncullable. Two interpenetrating blobs
// and a third one apart: only the third one's triangles are sampled, and the bounds and
// answers stay those of brute force.
TEST(Stage2, ObjectsProvenToTouchAreNotSampled) {
  test::Rng rng(11);
  Frame frame;
  frame.objects.push_back(test::make_blob(rng, Vec3(0, 0, 0), 0.5, 2, 0.05, "a"));
  frame.objects.push_back(test::make_blob(rng, Vec3(0.6, 0.1, 0), 0.5, 2, 0.05, "b"));
  frame.objects.push_back(test::make_blob(rng, Vec3(0.3, 1.1, 0), 0.5, 2, 0.05, "c"));
  const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
  const ObjectBroadPhase stage1 = object_broad_phase(frame, boxes, 2);
  ASSERT_EQ(stage1.upper_bound[0], 0.0);
  ASSERT_EQ(stage1.upper_bound[1], 0.0);
  ASSERT_GT(stage1.upper_bound[2], 0.0);
  const auto third = static_cast<std::uint64_t>(frame.objects[2].num_triangles());
  expect_bounds_at_grids(frame, {8, 24, 48}, "touching blobs", [&](const VoronoiBounds& vb) {
    EXPECT_GT(vb.sampled_triangles, 0u);
    EXPECT_LE(vb.sampled_triangles, third);
    EXPECT_EQ(vb.object_upper[0], 0.0);
    EXPECT_EQ(vb.object_upper[1], 0.0);
  });
}

// Stage II samples only where another object may lie within U_i (or the band, if shorter): a
// triangle whose box is farther than that from every other object's box is not sampled and
// gets a D_l of at least that (which culls it: Stage III looks within U_i + slack only), and of
// the others only the voxels within the band of some other object's triangle box are. Here a
// small blob sits over one corner of a large sheet: the sheet's far triangles are not sampled.
TEST(Stage2, OnlyTrianglesNearAnotherObjectAreSampled) {
  test::Rng rng(5);
  Frame frame;
  frame.objects.push_back(make_sheet(24, 10.0, "sheet"));
  frame.objects.push_back(test::make_blob(rng, Vec3(1.0, 1.0, 0.35), 0.25, 1, 0.1, "blob"));
  const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
  const ObjectBroadPhase stage1 = object_broad_phase(frame, boxes, 2);
  auto backend = make_cpu_voronoi_backend(2);
  const auto ref = inter_object_distance_brute_force(frame);
  // Grids at which the band (at most band_cap: kMaxInterBandCells cells of the grid or of the
  // default grid) reaches from the blob to the sheet, about 0.1 below it.
  for (int grid : {16, 64, 120}) {
    SCOPED_TRACE("grid " + std::to_string(grid));
    const VoronoiBounds vb = compute_voronoi_bounds(frame, boxes, stage1, *backend, grid, 2);
    const double cell = vb.grid.cell;
    // The sample voxels lie within the band (<= band_cap) of the blob's box, plus the sheet's
    // triangles' voxels around it: at most this many.
    const Vec3 reach = boxes.objects[1].hi - boxes.objects[1].lo + Vec3::Constant(2 * (vb.band_cap + 2 * cell));
    const double near_voxels = (reach / cell + Vec3::Ones()).prod();
    EXPECT_LE(static_cast<double>(vb.sample_voxels), near_voxels);
    EXPECT_LT(vb.sampled_triangles, static_cast<std::uint64_t>(frame.objects[0].num_triangles() / 4));
    // Sampled: only triangles within min(U_i, band) (+ rounding) of the other object, not all
    // within the band (U_i + δ).
    std::uint64_t within_u = 0;
    for (size_t i = 0; i < 2; ++i) {
      const double r = std::min(stage1.upper_bound[i], vb.band_cap) * 1.01 + 1e-9;
      for (const AABB& bt : boxes.triangles[i]) within_u += box_distance_squared(bt, boxes.objects[1 - i]) <= r * r;
    }
    EXPECT_LE(vb.sampled_triangles, within_u);
    // The backend gets the blob and the sheet's triangles near it only (in bins of 4 cells, 4
    // of the default grid on finer grids, around the samples: at grid 16 a quarter of the
    // sheet's bins).
    const auto blob = static_cast<std::uint64_t>(frame.objects[1].num_triangles());
    ASSERT_GE(vb.backend_triangles, blob);
    EXPECT_LT(vb.backend_triangles - blob, static_cast<std::uint64_t>(frame.objects[0].num_triangles() / 2));
    const double near0 = std::min(stage1.upper_bound[0], vb.band_cap);
    Index far = 0;
    for (size_t i = 0; i < 2; ++i) {
      EXPECT_GE(vb.object_upper[i], ref.per_object[i].distance);
      for (Index t = 0; t < frame.objects[i].num_triangles(); ++t) {
        const double lower = vb.triangle_lower[i][static_cast<size_t>(t)];
        ASSERT_LE(lower, exact_triangle_separation(frame, i, t)) << "object " << i << " triangle " << t;
        if (i == 0 && std::sqrt(box_distance_squared(boxes.triangles[0][static_cast<size_t>(t)], boxes.objects[1])) > near0) {
          ++far;
          ASSERT_GE(lower, near0) << "triangle " << t;
        }
      }
    }
    EXPECT_GT(far, frame.objects[0].num_triangles() / 2);
    InterDistanceOptions opts{2, &vb};
    const auto got = inter_object_distance(frame, boxes, stage1, opts);
    for (size_t i = 0; i < 2; ++i) {
      EXPECT_EQ(got.per_object[i].distance, ref.per_object[i].distance);
      EXPECT_EQ(got.per_object[i].triangles, ref.per_object[i].triangles);
    }
  }
}

// On grids finer than the default, the band's cap stays 2 cells of the default grid in scene
// units (VoronoiBounds::band_cap): capped at 2 of their own cells it shrank below the gap
// between objects, and no triangle could be culled. A blob 0.3 above a sheet (default grid 42
// cells of 0.24): at 200 and 400 cells, 2 cells (0.1, 0.05) are less than the gap, so no
// sheet triangle got a D_l above the answer (0 of 1,152); now those farther than the answer +
// 2δ from the blob do (1,146), which culls them.
TEST(Stage2, FineGridsKeepTheDefaultGridsBand) {
  test::Rng rng(9);
  Frame frame;
  frame.objects.push_back(make_sheet(24, 10.0, "sheet"));
  frame.objects.push_back(test::make_blob(rng, Vec3(5.0, 5.0, 0.55), 0.25, 1, 0.02, "blob"));
  const double answer = inter_object_distance_brute_force(frame).per_object[0].distance;
  ASSERT_GT(answer, 0.2);
  ASSERT_LT(answer, 0.4);
  const auto sheet = static_cast<std::uint64_t>(frame.objects[0].num_triangles());
  expect_bounds_at_grids(frame, {200, 400}, "blob over a sheet", [&](const VoronoiBounds& vb) {
    EXPECT_GT(vb.band_cap, 2 * vb.grid.cell);
    std::uint64_t culled = 0;
    for (const double lower : vb.triangle_lower[0]) culled += lower > answer;
    EXPECT_GT(culled, sheet * 9 / 10);
  });
}

// The same bounds on crowds where most triangles have another object within the band: blobs,
// and soups of slivers and large triangles between them, at coarse to fine grids.
TEST(Stage2, LowerBoundsHoldWhereOnlyPartOfTheVoxelsAreSampled) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    test::Rng rng(seed * 7919);
    Frame frame = test::make_random_frame(seed, 5, 2.0, 1);
    for (int k = 0; k < 3; ++k)
      frame.objects.push_back(test::make_soup(rng, Vec3(1.0, 1.0, 1.0), 1.2, k == 0 ? 0.05 : 0.6, 30,
                                              "soup" + std::to_string(k)));
    expect_bounds_at_grids(frame, {6, 20, 48, 96}, "seed " + std::to_string(seed), [](const VoronoiBounds&) {});
  }
}

// An object near many others (a floor under a crowd, a container) is filtered through the
// owner grid, not through each neighbour's hierarchy: its bounds, and those of the grains
// near it, must hold all the same.
TEST(Stage2, LowerBoundsHoldForAnObjectNearManyOthers) {
  for (std::uint64_t seed = 1; seed <= 2; ++seed) {
    test::Rng rng(seed * 31);
    Frame frame;
    frame.objects.push_back(make_sheet(20, 6.0, "floor"));
    for (int k = 0; k < 14; ++k) {
      const Vec3 c{rng.uniform(0.5, 3.0), rng.uniform(0.5, 3.0), rng.uniform(-0.1, 0.5)};
      frame.objects.push_back(test::make_blob(rng, c, rng.uniform(0.15, 0.3), 1, 0.2, "grain" + std::to_string(k)));
    }
    const auto all = static_cast<std::uint64_t>(frame.objects[0].num_triangles() + 14 * frame.objects[1].num_triangles());
    expect_bounds_at_grids(frame, {8, 30, 90, 200}, "seed " + std::to_string(seed), [&](const VoronoiBounds& vb) {
      // Not every triangle is sampled: the floor's part far from the grains is not.
      EXPECT_LT(vb.sampled_triangles, all);
    });
  }
}

// The sampling filter's tests reach past the band by their rounding error only. Far from the
// origin the frame's rounding slack (~4.5e5 ulps of the coordinates) spans the whole scene,
// and reaching past the band by it sampled everything (and scanned the owner grid across the
// scene for every voxel: 18 grains at 1e12 took 52 s at --grid 512). The same scene moved
// exactly by 2^40 must sample about what it does at the origin.
TEST(Stage2, SamplesFarFromTheOriginAboutWhatTheyDoAtIt) {
  // A floor and 12 small cubes above it, on dyadic coordinates (translated exactly).
  auto cube = [](const Vec3& lo, double side, const std::string& name) {
    std::vector<Vec3> v;
    for (int k = 0; k < 8; ++k) v.push_back(lo + side * Vec3(k & 1, (k >> 1) & 1, (k >> 2) & 1));
    const std::vector<Face> f = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                                 {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    return test::make_object(v, f, name);
  };
  Frame near_origin;
  near_origin.objects.push_back(make_sheet(16, 4.0, "floor"));
  for (int k = 0; k < 12; ++k)
    near_origin.objects.push_back(cube(Vec3(0.25 + 0.3125 * (k % 4), 0.5 + 0.75 * (k / 4), 0.0625 * (1 + k % 3)), 0.25,
                                       "cube" + std::to_string(k)));
  Frame far = near_origin;
  for (Object& o : far.objects)
    for (Vec3& p : o.positions) p += Vec3::Constant(0x1p40);
  auto backend = make_cpu_voronoi_backend(2);
  for (int grid : {32, 128}) {
    SCOPED_TRACE("grid " + std::to_string(grid));
    std::array<VoronoiBounds, 2> vb;
    for (int k = 0; k < 2; ++k) {
      const Frame& frame = k == 0 ? near_origin : far;
      const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
      const ObjectBroadPhase stage1 = object_broad_phase(frame, boxes, 2);
      vb[static_cast<size_t>(k)] = compute_voronoi_bounds(frame, boxes, stage1, *backend, grid, 2);
    }
    EXPECT_GT(vb[0].sample_voxels, 0u);
    // Far from the origin the triangles within the band are sampled, not only those within
    // U_i (below): at grid 128 (band_cap: 2 cells of the default grid, 7.3 of its own) that
    // is 2.1x the voxels.
    EXPECT_LE(vb[1].sample_voxels, 3 * vb[0].sample_voxels);
    // Near the origin only triangles within U_i of another object are sampled; far from it the
    // rounding slack (~110 at 2^40) widens that to the band, but no farther: at most the
    // triangles whose boxes lie within the band's cap of another object's triangle box, plus
    // the owner grid's coarseness (cells of two voxels: a widened box's cells reach up to a
    // cell's diagonal farther).
    const FrameBoxes boxes = FrameBoxes::compute(near_origin, 2);
    const double cap = (vb[0].band_cap + 2 * std::sqrt(3.0) * vb[0].grid.cell) * 1.01;
    std::uint64_t within_cap = 0;
    for (size_t i = 0; i < near_origin.objects.size(); ++i)
      for (const AABB& bt : boxes.triangles[i]) {
        bool hit = false;
        for (size_t j = 0; j < near_origin.objects.size() && !hit; ++j)
          if (j != i)
            for (const AABB& bo : boxes.triangles[j])
              if (box_distance_squared(bt, bo) <= cap * cap) {
                hit = true;
                break;
              }
        within_cap += hit;
      }
    EXPECT_LT(within_cap, static_cast<std::uint64_t>(near_origin.objects[0].num_triangles()));
    EXPECT_LE(vb[0].sampled_triangles, within_cap);
    EXPECT_LE(vb[1].sampled_triangles, within_cap);
  }
}

// --grid N means N cells along the longest axis: the quotient longest / N rounded down used to
// need an extra cell (--grid 50 gave 51 on a sample scene). The N cells must still cover the box.
TEST(Stage2, GridHasExactlyTheRequestedCellsAlongTheLongestAxis) {
  test::Rng rng(17);
  for (int trial = 0; trial < 20000; ++trial) {
    const int n = 1 + static_cast<int>(rng.uniform(0, 600));
    AABB box;
    box.extend(rng.vec3(-3, 3));
    box.extend(rng.vec3(-3, 3));
    const StageGrid sg = StageGrid::over(box, n);
    const Vec3 ext = box.hi - box.lo;
    int longest = 0;
    for (int k = 1; k < 3; ++k)
      if (ext[k] > ext[longest]) longest = k;
    ASSERT_EQ(sg.grid.dims[longest], n) << "trial " << trial << " extent " << ext[longest];
    for (int k = 0; k < 3; ++k) {
      ASSERT_LE(sg.grid.dims[k], n);
      // (Within rounding off the longest axis: the voxel slack covers that.)
      ASSERT_GE(sg.grid.cell * sg.grid.dims[k], ext[k] * (k == longest ? 1 : 1 - 1e-12)) << "trial " << trial;
    }
  }
}

/// Triangle number i of the voxelization tests, in `scene` (whose grid is g): of every shape,
/// by i % 5: ordinary, a sliver, exactly collinear, a single point, or lying in a grid plane
/// with a corner on a voxel corner; by i % 3 about 0.3, 2.5 or 12 cells across.
Triangle voxelization_test_triangle(test::Rng& rng, const AABB& scene, const VoronoiGrid& g, int i) {
  auto random_point = [&](const Vec3& around, double r) {
    Vec3 p;
    for (int k = 0; k < 3; ++k)
      p[k] = std::clamp(around[k] + rng.uniform(-r, r), scene.lo[k], scene.lo[k] + g.cell * g.dims[k]);
    return p;
  };
  const Vec3 centre = random_point(0.5 * (scene.lo + scene.hi), 0.5 * (scene.hi - scene.lo).maxCoeff());
  const double size = g.cell * (i % 3 == 0 ? 0.3 : i % 3 == 1 ? 2.5 : 12.0);
  Triangle tri{random_point(centre, size), random_point(centre, size), random_point(centre, size)};
  switch (i % 5) {
    case 1:  // sliver: the third corner almost on the first edge
      tri[2] = tri[0] + 0.37 * (tri[1] - tri[0]) + Vec3::Constant(1e-9 * g.cell);
      break;
    case 2:  // exactly collinear
      tri[2] = 0.5 * (tri[0] + tri[1]);
      break;
    case 3:  // a point
      tri[1] = tri[2] = tri[0];
      break;
    case 4: {  // in a grid plane, corners on voxel boundaries
      const int axis = i % 3;
      const double plane = scene.lo[axis] + g.cell * std::floor(g.dims[static_cast<size_t>(axis)] * rng.uniform(0, 1));
      for (Vec3& p : tri) p[axis] = plane;
      tri[0] = scene.lo + g.cell * Vec3(std::floor((tri[0] - scene.lo).x() / g.cell),
                                        std::floor((tri[0] - scene.lo).y() / g.cell),
                                        std::floor((tri[0] - scene.lo).z() / g.cell));
      break;
    }
    default:
      break;
  }
  return tri;
}

// The voxelization Lemma 2 rests on (StageGrid::voxelize): every voxel holding a point of the
// triangle is marked (checked at the corners and on a barycentric lattice), and every marked
// voxel's centre is within sqrt(3) * half of the triangle (so within δ). Triangles of every
// shape (voxelization_test_triangle()), small and large against the cell.
TEST(Stage2, VoxelizationMarksEveryTouchedVoxelAndOnlyNearOnes) {
  test::Rng rng(11);
  AABB scene;
  scene.extend(Vec3(-1.0, -2.0, -0.5));
  scene.extend(Vec3(3.0, 2.0, 1.5));
  const StageGrid sg = StageGrid::over(scene, 23);
  const VoronoiGrid& g = sg.grid;
  std::uint64_t marked_total = 0, checked_points = 0;
  for (int i = 0; i < 4000; ++i) {
    const Triangle tri = voxelization_test_triangle(rng, scene, g, i);
    AABB box;
    for (const Vec3& p : tri) box.extend(p);
    std::vector<std::int64_t> marked;
    sg.voxelize(tri, box, [&](std::int64_t id) { marked.push_back(id); });
    ASSERT_TRUE(std::is_sorted(marked.begin(), marked.end())) << "triangle " << i;
    ASSERT_FALSE(marked.empty()) << "triangle " << i;
    marked_total += marked.size();
    // Coverage: the voxel of every point of the triangle (corners, lattice points).
    constexpr int kLattice = 24;
    for (int a = 0; a <= kLattice; ++a)
      for (int b = 0; a + b <= kLattice; ++b) {
        const double u = static_cast<double>(a) / kLattice, v = static_cast<double>(b) / kLattice;
        const Vec3 p = (1 - u - v) * tri[0] + u * tri[1] + v * tri[2];
        std::int64_t id = 0, stride = 1;
        for (int k = 0; k < 3; ++k) {
          const auto cell = std::clamp<std::int64_t>(
              static_cast<std::int64_t>(std::floor((p[k] - g.origin[k]) / g.cell)), 0, g.dims[static_cast<size_t>(k)] - 1);
          id += cell * stride;
          stride *= g.dims[static_cast<size_t>(k)];
        }
        ++checked_points;
        ASSERT_TRUE(std::binary_search(marked.begin(), marked.end(), id))
            << "triangle " << i << ": the voxel of lattice point (" << a << ", " << b << ") is not marked";
      }
    // Tightness: marked voxel centres are within sqrt(3) * half of the triangle.
    for (const std::int64_t id : marked) {
      const std::int64_t x = id % g.dims[0], y = (id / g.dims[0]) % g.dims[1], z = id / (std::int64_t{g.dims[0]} * g.dims[1]);
      const Vec3 c = g.origin + g.cell * Vec3(static_cast<double>(x) + 0.5, static_cast<double>(y) + 0.5,
                                              static_cast<double>(z) + 0.5);
      ASSERT_LE(std::sqrt(point_triangle_distance(c, tri).squared_distance), std::sqrt(3.0) * sg.half * (1 + 1e-9))
          << "triangle " << i << " voxel " << id;
    }
  }
  // The triangles are not all tiny: the lattices and voxel lists are substantial.
  EXPECT_GT(marked_total, 50000u);
  EXPECT_GT(checked_points, 1000000u);
}

// voxelize_cells() tests only the cells of each row within the triangle's span along it; it
// must visit exactly the cells of the triangle's box range that the separating-axis test
// accepts, as testing every cell of the range does, in the same order. Scenes near and far
// from the origin, coarse and fine grids, triangles of every shape.
TEST(Stage2, VoxelizationVisitsWhatTestingEveryCellOfTheBoxFinds) {
  test::Rng rng(12);
  std::uint64_t visited_total = 0;
  for (const double offset : {0.0, -3.5e4, 1e9})
    for (const int res : {23, 160, 1024}) {
      AABB scene;
      scene.extend(Vec3(-1.0, -2.0, -0.5) + Vec3::Constant(offset));
      scene.extend(Vec3(3.0, 2.0, 1.5) + Vec3::Constant(offset));
      const StageGrid sg = StageGrid::over(scene, res);
      const VoronoiGrid& g = sg.grid;
      for (int i = 0; i < 1500; ++i) {
        const Triangle tri = voxelization_test_triangle(rng, scene, g, i);
        AABB box;
        for (const Vec3& p : tri) box.extend(p);
        std::vector<std::int64_t> visited, expected;
        sg.voxelize_cells(tri, box, [&](const StageGrid::Cell& c, std::int64_t id) {
          ASSERT_EQ(id, c[0] + std::int64_t{g.dims[0]} * (c[1] + std::int64_t{g.dims[1]} * c[2]));
          visited.push_back(id);
        });
        Triangle rel = tri;
        for (Vec3& p : rel) p -= g.origin;
        const TriangleBoxTester tester(rel, sg.half);
        const auto [lo, hi] = sg.cell_range(box);
        for (std::int32_t z = lo[2]; z <= hi[2]; ++z)
          for (std::int32_t y = lo[1]; y <= hi[1]; ++y)
            for (std::int32_t x = lo[0]; x <= hi[0]; ++x)
              if (tester.overlaps(g.cell * Vec3(x + 0.5, y + 0.5, z + 0.5)))
                expected.push_back(x + std::int64_t{g.dims[0]} * (y + std::int64_t{g.dims[1]} * z));
        ASSERT_EQ(visited, expected) << "offset " << offset << ", grid " << res << ", triangle " << i;
        visited_total += visited.size();
      }
    }
  EXPECT_GT(visited_total, 200000u);
}

}  // namespace
}  // namespace vproxq
