// Stage II contract (Lemma 2): D_u(O_i) bounds each object's exact separation distance from
// above, D_l(f) bounds each triangle's from below, and culling with them changes no answer.
#include "core/geometry/point_triangle.hpp"
#include "core/query/inter_distance.hpp"
#include "core/voronoi/grid_setup.hpp"
#include "core/voronoi/stage2.hpp"
#include "support/random_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace vproxq {
namespace {

TEST(Stage2, BoundsHoldAndResultsEqualBruteForce) {
  auto backend = make_cpu_voronoi_backend(2);
  for (std::uint64_t seed = 1; seed <= 6; ++seed) {
    const Frame frame = test::make_random_frame(seed, 8, 1.5 + 0.5 * static_cast<double>(seed % 3), 1);
    const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
    const ObjectBroadPhase stage1 = object_broad_phase(frame, boxes, 2);
    const auto ref = inter_object_distance_brute_force(frame);
    for (int grid : {8, 24, 64}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + " grid " + std::to_string(grid));
      const VoronoiBounds vb = compute_voronoi_bounds(frame, boxes, stage1, *backend, grid, 2);
      EXPECT_GT(vb.delta, 0.0);
      for (size_t i = 0; i < frame.objects.size(); ++i) {
        EXPECT_GE(vb.object_upper[i], ref.per_object[i].distance) << "object " << i;
        const Object& oi = frame.objects[i];
        for (Index t = 0; t < oi.num_triangles(); ++t) {
          double sd = kInfinity;  // exact distance of triangle t to every other object
          for (size_t j = 0; j < frame.objects.size(); ++j) {
            if (j == i) continue;
            for (Index u = 0; u < frame.objects[j].num_triangles(); ++u)
              sd = std::min(sd, triangle_distance(oi.triangle(t), frame.objects[j].triangle(u)).distance);
          }
          ASSERT_LE(vb.triangle_lower[i][static_cast<size_t>(t)], sd) << "object " << i << " triangle " << t;
        }
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
  }
}

// --grid N means N cells along the longest axis: the quotient longest / N rounded down used to
// need an extra cell (--grid 50 gave 51 on a sample scene). The N cells must still cover the box.
TEST(Stage2, GridHasExactlyTheRequestedCellsAlongTheLongestAxis) {
  test::Rng rng(17);
  for (int trial = 0; trial < 20000; ++trial) {
    const int n = 1 + static_cast<int>(rng.uniform(0, 600));
    AABB box;
    box.extend(Vec3(rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-3, 3)));
    box.extend(Vec3(rng.uniform(-3, 3), rng.uniform(-3, 3), rng.uniform(-3, 3)));
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

// The voxelization Lemma 2 rests on (StageGrid::voxelize): every voxel holding a point of the
// triangle is marked (checked at the corners and on a barycentric lattice), and every marked
// voxel's centre is within sqrt(3) * half of the triangle (so within δ). Triangles of every
// shape: ordinary, slivers, exactly collinear, single points, and triangles lying in a grid
// plane (coordinates on voxel boundaries), small and large against the cell.
TEST(Stage2, VoxelizationMarksEveryTouchedVoxelAndOnlyNearOnes) {
  test::Rng rng(11);
  AABB scene;
  scene.extend(Vec3(-1.0, -2.0, -0.5));
  scene.extend(Vec3(3.0, 2.0, 1.5));
  const StageGrid sg = StageGrid::over(scene, 23);
  const VoronoiGrid& g = sg.grid;
  auto random_point = [&](const Vec3& around, double r) {
    Vec3 p;
    for (int k = 0; k < 3; ++k)
      p[k] = std::clamp(around[k] + rng.uniform(-r, r), scene.lo[k], scene.lo[k] + g.cell * g.dims[k]);
    return p;
  };
  std::uint64_t marked_total = 0, checked_points = 0;
  for (int i = 0; i < 4000; ++i) {
    const Vec3 centre = random_point(0.5 * (scene.lo + scene.hi), 2.0);
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

}  // namespace
}  // namespace vproxq
