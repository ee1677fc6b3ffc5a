// Stage II contract (Lemma 2): D_u(O_i) bounds each object's exact separation distance from
// above, D_l(f) bounds each triangle's from below, and culling with them changes no answer.
#include "core/query/inter_distance.hpp"
#include "core/voronoi/stage2.hpp"
#include "support/random_scene.hpp"

#include <gtest/gtest.h>

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

}  // namespace
}  // namespace vproxq
