// The triangle hierarchy's per-node summaries against direct loops over the triangles.
#include "core/broad_phase/triangle_bvh.hpp"
#include "support/random_scene.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace vproxq {
namespace {

using test::Rng;

std::vector<AABB> random_boxes(Rng& rng, int n) {
  std::vector<AABB> boxes;
  for (int t = 0; t < n; ++t) {
    const Vec3 c(rng.uniform(0, 10), rng.uniform(0, 10), rng.uniform(0, 10));
    const Vec3 h(rng.uniform(0, 1.5), rng.uniform(0, 1.5), rng.uniform(0, 1.5));
    AABB b;
    b.extend(c - h);
    b.extend(c + h);
    boxes.push_back(b);
  }
  return boxes;
}

// A search from f that passes over every subtree whose largest id is at most f (what CCD's
// self search does) meets exactly the triangles of larger id whose boxes overlap f's.
TEST(TriangleBvh, SubtreesOfSmallerIdsHoldOnlySmallerIds) {
  for (std::uint64_t seed = 1; seed <= 12; ++seed) {
    Rng rng(seed);
    const int n = rng.integer(1, 300);
    const std::vector<AABB> boxes = random_boxes(rng, n);
    TriangleBvh bvh;
    bvh.build(boxes);
    const std::vector<Index> max_id = bvh.node_max_ids();
    for (Index f = 0; f < n; ++f) {
      std::vector<Index> met;
      bvh.query_overlaps(boxes[static_cast<size_t>(f)],
                         [&](std::int32_t node) { return max_id[static_cast<size_t>(node)] <= f; },
                         [&](Index g) {
                           if (g > f) met.push_back(g);
                         });
      std::sort(met.begin(), met.end());
      std::vector<Index> expect;
      for (Index g = f + 1; g < n; ++g)
        if (boxes_overlap(boxes[static_cast<size_t>(f)], boxes[static_cast<size_t>(g)])) expect.push_back(g);
      ASSERT_EQ(met, expect) << "seed " << seed << " triangle " << f;
    }
  }
}

}  // namespace
}  // namespace vproxq
