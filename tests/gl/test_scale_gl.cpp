// The GL Stage II backends at scene scales past float32's range: the host hands them lengths
// in units of a power of two near the grid's extent, so a scene scaled by 2^-150 or 2^150 gets
// the same float32 input as at scale 1, and bounds scaled exactly by the same power of two.
// Before, lengths went to the shaders in scene units: at 2^-150 they were all 0 in float32,
// at 2^150 all inf.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "core/broad_phase/object_broad_phase.hpp"
#include "core/query/inter_distance.hpp"
#include "core/query/intra_distance.hpp"
#include "core/voronoi/self_stage2.hpp"
#include "core/voronoi/stage2.hpp"
#include "gl/self_voronoi_backend.hpp"
#include "gl/voronoi_backend.hpp"
#include "gl_test_support.hpp"
#include "support/expect_same.hpp"
#include "support/random_scene.hpp"
#include "support/self_meshes.hpp"

namespace vproxq::gl {
namespace {

Frame scaled_frame(const Frame& base, int k) {
  Frame f = base;
  for (Object& o : f.objects)
    for (Vec3& p : o.positions) p = Vec3(std::ldexp(p.x(), k), std::ldexp(p.y(), k), std::ldexp(p.z(), k));
  return f;
}

TEST(GlScale, PowerOfTwoScalesScaleTheBoundsAndKeepTheAnswers) {
  VPROXQ_GL_CONTEXT_OR_FAIL(context);
  GlVoronoiBackend inter_backend(context);
  GlSelfVoronoiBackend self_backend(context);
  std::uint64_t bounded = 0;
  for (std::uint64_t seed = 41; seed <= 43; ++seed) {
    Frame base = test::make_random_frame(seed, 5, 1.5, 1);
    test::Rng rng(seed);
    base.objects.push_back(test::make_folded_sheet(rng, 10, 5, 0.1, 0.05, 0.02, "sheet"));
    struct Run {
      VoronoiBounds vb;
      SelfVoronoiBounds sb;
    };
    auto run_at = [&](int k) {
      const Frame frame = scaled_frame(base, k);
      const FrameBoxes boxes = FrameBoxes::compute(frame, 1);
      const ObjectBroadPhase stage1 = object_broad_phase(frame, boxes, 1);
      const auto ring2 = ring2_upper_bounds(frame, 1);
      Run r{compute_voronoi_bounds(frame, boxes, stage1, inter_backend, 32, 1),
            compute_self_voronoi_bounds(frame, boxes, ring2, self_backend, 48, 1)};
      // And the answers equal brute force with these bounds.
      test::expect_same_inter(inter_object_distance(frame, boxes, stage1, InterDistanceOptions{1, &r.vb}),
                              inter_object_distance_brute_force(frame), "inter gpu");
      test::expect_same_intra(intra_object_distance(frame, boxes, ring2, IntraDistanceOptions{1, &r.sb}),
                              intra_object_distance_brute_force(frame), "intra gpu");
      return r;
    };
    const Run one = run_at(0);
    for (const auto& per_object : one.vb.triangle_lower)
      for (const double d : per_object) bounded += d > -kInfinity;
    for (const auto& per_object : one.sb.triangle_lower)
      for (const double d : per_object) bounded += d > -kInfinity;
    for (const int k : {-150, 150}) {
      SCOPED_TRACE("seed " + std::to_string(seed) + ", scale 2^" + std::to_string(k));
      const Run r = run_at(k);
      EXPECT_EQ(r.vb.delta, std::ldexp(one.vb.delta, k));
      EXPECT_EQ(r.sb.delta, std::ldexp(one.sb.delta, k));
      for (size_t i = 0; i < one.vb.triangle_lower.size(); ++i) {
        EXPECT_EQ(r.vb.object_upper[i], std::ldexp(one.vb.object_upper[i], k)) << "object " << i;
        for (size_t t = 0; t < one.vb.triangle_lower[i].size(); ++t)
          ASSERT_EQ(r.vb.triangle_lower[i][t], std::ldexp(one.vb.triangle_lower[i][t], k))
              << "object " << i << " triangle " << t;
      }
      for (size_t i = 0; i < one.sb.triangle_lower.size(); ++i)
        for (size_t t = 0; t < one.sb.triangle_lower[i].size(); ++t) {
          ASSERT_EQ(r.sb.triangle_lower[i][t], std::ldexp(one.sb.triangle_lower[i][t], k))
              << "object " << i << " triangle " << t;
          ASSERT_EQ(r.sb.triangle_upper[i][t], std::ldexp(one.sb.triangle_upper[i][t], k))
              << "object " << i << " triangle " << t;
        }
    }
  }
  EXPECT_GT(bounded, 500u);  // the bounds compared are real ones, not -inf everywhere
}

}  // namespace
}  // namespace vproxq::gl
