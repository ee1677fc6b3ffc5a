// Stage I's per-axis search (the interval overlapping a given one the most) against a scan of
// every other interval, and its segment tree against direct loops.
#include "core/broad_phase/sorted_axis.hpp"
#include "support/random_scene.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <string>

namespace vproxq {
namespace {

using test::Rng;

TEST(MaxTree, RangeMaximaAndFirstMatchEqualDirectLoops) {
  for (std::uint64_t seed = 1; seed <= 20; ++seed) {
    Rng rng(seed);
    const int n = rng.integer(1, 70);  // sizes on both sides of powers of two
    std::vector<double> v;
    for (int q = 0; q < n; ++q) v.push_back(static_cast<double>(rng.integer(-5, 5)));  // many ties
    const MaxTree tree(v);
    for (size_t l = 0; l <= v.size(); ++l)
      for (size_t r = l; r <= v.size(); ++r) {
        const std::string where = "seed " + std::to_string(seed) + " [" + std::to_string(l) + ", " +
                                  std::to_string(r) + ")";
        double m = -kInfinity;
        for (size_t q = l; q < r; ++q) m = std::max(m, v[q]);
        EXPECT_EQ(tree.max(l, r), m) << where;
        for (double t = -6; t <= 6; t += 1) {
          size_t expect = r;
          for (size_t q = l; q < r && expect == r; ++q)
            if (v[q] >= t) expect = q;
          EXPECT_EQ(tree.first(l, r, [&](double x) { return x >= t; }), expect) << where << " t " << t;
        }
      }
  }
}

// What Stage I did before the search: every other object in sorted order, strict improvements.
Index scan_most_overlapping(const std::vector<Index>& objects, const std::vector<AABB>& boxes, int k, Index i) {
  std::vector<Index> order = objects;
  std::sort(order.begin(), order.end(), [&](Index a, Index b) {
    const double la = boxes[static_cast<size_t>(a)].lo[k], lb = boxes[static_cast<size_t>(b)].lo[k];
    return la < lb || (la == lb && a < b);
  });
  Index best = kNoIndex;
  double best_overlap = -kInfinity;
  for (Index j : order) {
    if (j == i) continue;
    const double ov = interval_overlap(boxes[static_cast<size_t>(i)], boxes[static_cast<size_t>(j)], k);
    if (ov > best_overlap) {
      best_overlap = ov;
      best = j;
    }
  }
  return best;
}

TEST(SortedAxis, MostOverlappingEqualsAScanOfEveryOtherObject) {
  int picked_from_left = 0, picked_from_right = 0;
  for (std::uint64_t seed = 1; seed <= 60; ++seed) {
    Rng rng(seed);
    const int n = rng.integer(1, 60);
    // Integer ends in a small range give ties in lo, in hi and in the overlap; wide ranges give
    // nested and disjoint intervals; seeds past 30 use fractional ends (rounded overlaps).
    const int range = seed % 3 == 0 ? 4 : seed % 3 == 1 ? 20 : 200;
    std::vector<AABB> boxes(static_cast<size_t>(n) + 5);  // ids with gaps: some are left out
    std::vector<Index> objects;
    for (int id = 0; id < n + 5; ++id) {
      AABB& b = boxes[static_cast<size_t>(id)];
      for (int k = 0; k < 3; ++k) {
        double a = rng.integer(0, range), w = rng.integer(0, range / 2);
        if (seed > 30) {
          a = a * 0.1 + rng.uniform(0, 1e-3);
          w = w * 0.3 + rng.uniform(0, 1e-3);
        }
        b.lo[k] = a;
        b.hi[k] = a + w;
      }
      if (id % 7 != 3) objects.push_back(id);
    }
    for (int k = 0; k < 3; ++k) {
      const SortedAxis axis(objects, boxes, k);
      for (Index i : objects) {
        const Index got = axis.most_overlapping(i);
        EXPECT_EQ(got, scan_most_overlapping(objects, boxes, k, i)) << "seed " << seed << " axis " << k << " object " << i;
        if (got != kNoIndex)
          ++(boxes[static_cast<size_t>(got)].lo[k] <= boxes[static_cast<size_t>(i)].lo[k] ? picked_from_left
                                                                                              : picked_from_right);
      }
    }
  }
  // Both halves of the search were exercised.
  EXPECT_GT(picked_from_left, 100);
  EXPECT_GT(picked_from_right, 100);
}

}  // namespace
}  // namespace vproxq
