// Discrete collisions with the GL Stage II backend's bounds: the intersecting-pair list equals
// the all-pairs brute force (the culling with D_l > 0 must never drop an intersecting pair).
#include "core/query/intersecting_pairs.hpp"
#include "core/voronoi/stage2.hpp"
#include "gl/voronoi_backend.hpp"
#include "gl_test_support.hpp"
#include "support/random_scene.hpp"

#include <gtest/gtest.h>

namespace vproxq::gl {
namespace {

TEST(GlIntersectingPairs, EqualBruteForceOnRandomScenes) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  GlVoronoiBackend backend(context);
  size_t total = 0;
  for (std::uint64_t seed = 31; seed <= 34; ++seed) {
    Frame frame = test::make_random_frame(seed, 6, 1.2, 1);
    test::Rng rng(seed);
    frame.objects.push_back(test::make_soup(rng, Vec3(0.6, 0.6, 0.6), 0.5, 0.3, 20, "soup"));
    const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
    const ObjectBroadPhase stage1 = object_broad_phase(frame, boxes, 2);
    const auto ref = intersecting_pairs_brute_force(frame);
    total += ref.pairs.size();
    for (int grid : {16, 40}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + " grid " + std::to_string(grid));
      const VoronoiBounds vb = compute_voronoi_bounds(frame, boxes, stage1, backend, grid, 2);
      EXPECT_EQ(intersecting_pairs(frame, boxes, {2, &vb, true}).pairs, ref.pairs);
    }
  }
  EXPECT_GT(total, 20u);
}

}  // namespace
}  // namespace vproxq::gl
