#pragma once
// Bitwise comparisons of query results with their brute force, shared by the suites that
// compare them.
#include "core/query/ccd.hpp"
#include "core/query/inter_distance.hpp"
#include "core/query/intra_distance.hpp"

#include <gtest/gtest.h>

#include <string>

namespace vproxq::test {

/// Pipeline and brute force must agree exactly: both evaluate the same triangle pairs in the
/// same canonical order, so the winning pair and every number are bitwise identical.
inline void expect_same_inter(const InterDistanceOutput& got, const InterDistanceOutput& ref,
                              const std::string& what) {
  ASSERT_EQ(got.per_object.size(), ref.per_object.size()) << what;
  for (size_t i = 0; i < ref.per_object.size(); ++i) {
    const auto& g = got.per_object[i];
    const auto& r = ref.per_object[i];
    SCOPED_TRACE(what + ", object " + std::to_string(i));
    EXPECT_EQ(g.object, r.object);
    EXPECT_EQ(g.nearest_object, r.nearest_object);
    EXPECT_EQ(g.distance, r.distance);
    EXPECT_EQ(g.triangles, r.triangles);
    EXPECT_EQ(g.points[0], r.points[0]);
    EXPECT_EQ(g.points[1], r.points[1]);
    EXPECT_EQ(g.kind, r.kind);
  }
}

/// Per-triangle tables and minima must be bitwise equal: pipeline and brute force evaluate
/// the same pairs in the same canonical order.
inline void expect_same_intra(const IntraDistanceOutput& got, const IntraDistanceOutput& ref,
                              const std::string& what) {
  ASSERT_EQ(got.per_object.size(), ref.per_object.size()) << what;
  for (size_t i = 0; i < ref.per_object.size(); ++i) {
    const auto& g = got.per_object[i];
    const auto& r = ref.per_object[i];
    SCOPED_TRACE(what + ", object " + std::to_string(i));
    EXPECT_EQ(g.object, r.object);
    EXPECT_EQ(g.distance, r.distance);
    EXPECT_EQ(g.triangles, r.triangles);
    EXPECT_EQ(g.points[0], r.points[0]);
    EXPECT_EQ(g.points[1], r.points[1]);
    ASSERT_EQ(g.per_triangle.size(), r.per_triangle.size());
    int mismatches = 0;
    for (size_t t = 0; t < r.per_triangle.size(); ++t) {
      const auto& a = g.per_triangle[t];
      const auto& b = r.per_triangle[t];
      const bool same = a.nearest == b.nearest && a.distance == b.distance &&
                        a.points[0] == b.points[0] && a.points[1] == b.points[1] && a.kind == b.kind;
      if (!same && ++mismatches <= 5)
        ADD_FAILURE() << "triangle " << t << ": got " << a.nearest << " at " << a.distance
                      << ", brute force " << b.nearest << " at " << b.distance;
    }
    EXPECT_EQ(mismatches, 0);
  }
}

/// Identical vertex–face and edge–edge lists (ids and TOIs), per-pair summaries and skipped
/// objects.
inline void expect_same_ccd(const CcdStepResult& a, const CcdStepResult& b) {
  ASSERT_EQ(a.vf.size(), b.vf.size());
  for (size_t k = 0; k < a.vf.size(); ++k) {
    EXPECT_EQ(a.vf[k].object_v, b.vf[k].object_v);
    EXPECT_EQ(a.vf[k].vertex, b.vf[k].vertex);
    EXPECT_EQ(a.vf[k].object_f, b.vf[k].object_f);
    EXPECT_EQ(a.vf[k].face, b.vf[k].face);
    EXPECT_EQ(a.vf[k].toi, b.vf[k].toi);
  }
  ASSERT_EQ(a.ee.size(), b.ee.size());
  for (size_t k = 0; k < a.ee.size(); ++k) {
    EXPECT_EQ(a.ee[k].object_a, b.ee[k].object_a);
    EXPECT_EQ(a.ee[k].edge_a, b.ee[k].edge_a);
    EXPECT_EQ(a.ee[k].object_b, b.ee[k].object_b);
    EXPECT_EQ(a.ee[k].edge_b, b.ee[k].edge_b);
    EXPECT_EQ(a.ee[k].toi, b.ee[k].toi);
  }
  ASSERT_EQ(a.pairs.size(), b.pairs.size());
  for (size_t k = 0; k < a.pairs.size(); ++k) {
    EXPECT_EQ(a.pairs[k].objects, b.pairs[k].objects);
    EXPECT_EQ(a.pairs[k].toi, b.pairs[k].toi);
    EXPECT_EQ(a.pairs[k].primitive_pairs, b.pairs[k].primitive_pairs);
  }
  ASSERT_EQ(a.skipped.size(), b.skipped.size());
  for (size_t k = 0; k < a.skipped.size(); ++k) {
    EXPECT_EQ(a.skipped[k].object, b.skipped[k].object);
    EXPECT_EQ(a.skipped[k].reason, b.skipped[k].reason);
  }
}

}  // namespace vproxq::test
