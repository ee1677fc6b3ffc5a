#pragma once
// Brute-force checks of penetration-depth entries between two objects, shared by the PD tests
// (tests/core/test_penetration_depth.cpp) and the PD fuzz harness (tests/fuzz/fuzz_pd.cpp):
// the deepest vertex by exact max-min over every face, the inside vertices against the
// brute-force winding number, what a self_intersection entry's reason says, and the
// comparison of two results field by field.
#include "core/geometry/exact_distance.hpp"
#include "core/geometry/point_triangle.hpp"
#include "core/geometry/predicates.hpp"
#include "core/geometry/triangle_intersection.hpp"
#include "core/mesh/adjacency.hpp"
#include "core/query/penetration_depth.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <string>
#include <tuple>
#include <vector>

namespace vproxq::test {

/// The deepest vertex of an entry between two objects by brute force in exact arithmetic, as
/// docs/algorithms.md defines it: each inside vertex's exact distance to every triangle of the other
/// object (its nearest point on the lowest-numbered of equally near triangles), the largest of
/// them (ties: objects[0]'s vertices first, then the smallest vertex id). For speed, only
/// triangles (and vertices) whose double-precision distance is within a margin of the nearest
/// (the deepest) are compared exactly: 2^-30 of the largest coordinate magnitude, which is
/// hundreds of thousands of times the rounding of a computed distance.
struct ExactDeepest {
  Index object = kNoIndex, vertex = kNoIndex;
  Vec3 nearest = Vec3::Zero();
  int tied = 0;  ///< inside vertices exactly as deep as the deepest (itself included)
};
inline ExactDeepest exact_deepest(const Frame& frame, const PenetrationDepth& pd) {
  double magnitude = 0;
  for (Index k : pd.objects)
    for (const Vec3& p : frame.objects[static_cast<size_t>(k)].positions) magnitude = std::max(magnitude, p.cwiseAbs().maxCoeff());
  const double margin = 0x1p-30 * magnitude;
  struct Candidate {
    Index object, vertex;
    Vec3 point;
    Index face;
    double distance;
  };
  std::vector<Candidate> all;
  for (size_t side = 0; side < 2; ++side) {
    const Object& other = frame.objects[static_cast<size_t>(pd.objects[1 - side])];
    for (Index v : pd.inside_vertices[side]) {
      const Vec3& p = frame.objects[static_cast<size_t>(pd.objects[side])].positions[static_cast<size_t>(v)];
      std::vector<double> d(static_cast<size_t>(other.num_triangles()));
      for (Index t = 0; t < other.num_triangles(); ++t)
        d[static_cast<size_t>(t)] = std::sqrt(point_triangle_distance(p, other.triangle(t)).squared_distance);
      const double least = *std::min_element(d.begin(), d.end());
      Index face = kNoIndex;
      ExactFraction nearest;
      for (Index t = 0; t < other.num_triangles(); ++t) {
        if (d[static_cast<size_t>(t)] > least + margin) continue;
        ExactFraction e = exact_point_triangle_squared_distance(p, other.triangle(t));
        if (face == kNoIndex || compare(e, nearest) < 0) {
          nearest = std::move(e);
          face = t;
        }
      }
      all.push_back({pd.objects[side], v, p, face, least});
    }
  }
  ExactDeepest out;
  if (all.empty()) return out;
  double most = 0;
  for (const Candidate& c : all) most = std::max(most, c.distance);
  ExactFraction deepest;
  for (const Candidate& c : all) {  // objects[0]'s side first, vertices ascending
    if (c.distance < most - margin) continue;
    const Object& other = frame.objects[static_cast<size_t>(c.object == pd.objects[0] ? pd.objects[1] : pd.objects[0])];
    ExactFraction e = exact_point_triangle_squared_distance(c.point, other.triangle(c.face));
    const int order = out.vertex == kNoIndex ? 1 : compare(e, deepest);
    if (order > 0) {
      deepest = std::move(e);
      out = {c.object, c.vertex, point_triangle_distance(c.point, other.triangle(c.face)).closest, 1};
    } else if (order == 0) {
      ++out.tied;
    }
  }
  return out;
}

/// Checks the inside vertices of an entry between two objects (status ok or too_deep) against
/// the brute-force winding number (every face, no hierarchy): on each side, the listed
/// vertices are exactly those reached from the vertices of the entry's intersecting triangles
/// (`pairs`: the frame's intersecting pairs) through vertices inside the other object. Returns
/// how many vertices were listed.
inline size_t expect_inside_is_walk_closure(const Frame& frame, const PenetrationDepth& e,
                                            const std::vector<IntersectingPair>& pairs) {
  size_t listed_count = 0;
  for (int side = 0; side < 2; ++side) {
    const Object& own = frame.objects[static_cast<size_t>(e.objects[static_cast<size_t>(side)])];
    const Object& other = frame.objects[static_cast<size_t>(e.objects[static_cast<size_t>(1 - side)])];
    auto inside = [&](Index v) {
      bool on = false;
      const int w = winding_number_brute_force(own.positions[static_cast<size_t>(v)], other, on);
      return !on && w != 0;
    };
    const auto& list = e.inside_vertices[static_cast<size_t>(side)];
    auto listed = [&](Index v) { return std::binary_search(list.begin(), list.end(), v); };
    for (Index v : list) EXPECT_TRUE(inside(v)) << "side " << side << " vertex " << v;
    for (const IntersectingPair& p : pairs) {  // the walk's seeds
      if (p.object_a != e.objects[0] || p.object_b != e.objects[1]) continue;
      for (Index v : own.topology->faces[static_cast<size_t>(side == 0 ? p.tri_a : p.tri_b)])
        EXPECT_EQ(listed(v), inside(v)) << "side " << side << " seed vertex " << v;
    }
    const Adjacency& adj = adjacency(*own.topology);
    for (Index v : list)  // closed under inside neighbours
      for (Index t : adj.vertex_triangles(v))
        for (Index u : own.topology->faces[static_cast<size_t>(t)])
          if (!listed(u)) {
            EXPECT_FALSE(inside(u)) << "side " << side << " neighbour " << u << " of " << v;
          }
    listed_count += list.size();
  }
  return listed_count;
}

/// Whether some connected set of an entry's listed inside vertices (on either side, connected
/// through shared triangles) has no neighbour outside the list: docs/algorithms.md's too_deep. With the
/// list the walk closure (expect_inside_is_walk_closure), a neighbour not listed is outside.
inline bool has_swallowed_set(const Frame& frame, const PenetrationDepth& e) {
  for (int side = 0; side < 2; ++side) {
    const Object& own = frame.objects[static_cast<size_t>(e.objects[static_cast<size_t>(side)])];
    const auto& list = e.inside_vertices[static_cast<size_t>(side)];
    auto listed = [&](Index v) { return std::binary_search(list.begin(), list.end(), v); };
    const Adjacency& adj = adjacency(*own.topology);
    std::vector<char> seen(static_cast<size_t>(own.num_vertices()), 0);
    for (Index start : list) {
      if (seen[static_cast<size_t>(start)]) continue;
      bool meets_outside = false;
      std::vector<Index> stack = {start};
      seen[static_cast<size_t>(start)] = 1;
      while (!stack.empty()) {
        const Index v = stack.back();
        stack.pop_back();
        for (Index t : adj.vertex_triangles(v))
          for (Index u : own.topology->faces[static_cast<size_t>(t)]) {
            if (!listed(u)) {
              meets_outside = true;
            } else if (!seen[static_cast<size_t>(u)]) {
              seen[static_cast<size_t>(u)] = 1;
              stack.push_back(u);
            }
          }
      }
      if (!meets_outside) return true;
    }
  }
  return false;
}

/// An entry has a reason exactly when it is self_intersection, and the reason's feature has
/// the property it names (docs/algorithms.md, "Where it gives no number"): degenerate_star, a vertex of
/// the object all of whose faces are degenerate; flat_fold, a vertex two of whose faces lie in
/// one plane; reference_vertex, the lexicographically largest vertex (x, y, z, then id) of its
/// mesh component; sheets_not_separated, an intersecting pair of the object; whole_object,
/// a vertex of the object. `pairs`: the frame's intersecting pairs.
inline void expect_reason_holds(const Frame& frame, const PenetrationDepth& e,
                                const std::vector<IntersectingPair>& pairs) {
  if (e.status != PdStatus::SelfIntersection) {
    EXPECT_EQ(e.reason, PdReason::None) << pd_reason_name(e.reason);
    EXPECT_EQ(e.reason_features, (std::array<Index, 2>{kNoIndex, kNoIndex}));
    return;
  }
  SCOPED_TRACE(std::string("reason ") + pd_reason_name(e.reason));
  ASSERT_EQ(e.objects[0], e.objects[1]);
  const Object& o = frame.objects[static_cast<size_t>(e.objects[0])];
  const auto [a, b] = e.reason_features;
  if (e.reason == PdReason::SheetsNotSeparated) {
    const IntersectingPair p{e.objects[0], std::min(a, b), e.objects[0], std::max(a, b)};
    EXPECT_TRUE(a != b && std::find(pairs.begin(), pairs.end(), p) != pairs.end()) << a << " " << b;
    return;
  }
  EXPECT_EQ(b, kNoIndex);
  ASSERT_TRUE(a >= 0 && a < o.num_vertices()) << a;
  const IndexSpan star = adjacency(*o.topology).vertex_triangles(a);
  ASSERT_FALSE(star.empty());
  switch (e.reason) {
    case PdReason::DegenerateStar:
      for (Index t : star) EXPECT_TRUE(triangle_is_degenerate(o.triangle(t))) << t;
      break;
    case PdReason::FlatFold: {
      bool coplanar = false;
      for (Index f : star)
        for (Index g : star) {
          const Triangle tf = o.triangle(f), tg = o.triangle(g);
          if (f == g || triangle_is_degenerate(tf) || triangle_is_degenerate(tg)) continue;
          bool all = true;
          for (const Vec3& x : tg) all = all && orient3d(tf[0], tf[1], tf[2], x) == 0;
          coplanar = coplanar || all;
        }
      EXPECT_TRUE(coplanar) << a;
      break;
    }
    case PdReason::ReferenceVertex: {
      // a's component: the vertices reached from a across faces.
      std::vector<char> in(static_cast<size_t>(o.num_vertices()), 0);
      in[static_cast<size_t>(a)] = 1;
      for (bool grew = true; grew;) {
        grew = false;
        for (const Face& f : o.topology->faces)
          if ((in[static_cast<size_t>(f[0])] || in[static_cast<size_t>(f[1])] || in[static_cast<size_t>(f[2])]) &&
              !(in[static_cast<size_t>(f[0])] && in[static_cast<size_t>(f[1])] && in[static_cast<size_t>(f[2])])) {
            for (Index v : f) in[static_cast<size_t>(v)] = 1;
            grew = true;
          }
      }
      const Vec3& pa = o.positions[static_cast<size_t>(a)];
      for (Index v = 0; v < o.num_vertices(); ++v) {
        const Vec3& pv = o.positions[static_cast<size_t>(v)];
        if (in[static_cast<size_t>(v)]) {
          EXPECT_TRUE(std::tie(pa.x(), pa.y(), pa.z(), a) >= std::tie(pv.x(), pv.y(), pv.z(), v)) << a << " vs " << v;
        }
      }
      break;
    }
    case PdReason::WholeObject:
      break;
    default:
      ADD_FAILURE() << "self_intersection without a reason";
  }
}

/// Two results of the same frame are the same, every field (NaN equal to NaN).
inline void expect_same_pd(const std::vector<PenetrationDepth>& a, const std::vector<PenetrationDepth>& b,
                           const std::string& what) {
  ASSERT_EQ(a.size(), b.size()) << what;
  auto same = [](double x, double y) { return x == y || (std::isnan(x) && std::isnan(y)); };
  auto same_vec = [&](const Vec3& x, const Vec3& y) { return same(x[0], y[0]) && same(x[1], y[1]) && same(x[2], y[2]); };
  for (size_t k = 0; k < a.size(); ++k) {
    SCOPED_TRACE(what + ", entry " + std::to_string(k));
    EXPECT_EQ(a[k].objects, b[k].objects);
    EXPECT_EQ(a[k].status, b[k].status);
    EXPECT_TRUE(same(a[k].depth, b[k].depth)) << a[k].depth << " vs " << b[k].depth;
    EXPECT_TRUE(same_vec(a[k].direction, b[k].direction));
    EXPECT_EQ(a[k].deepest_object, b[k].deepest_object);
    EXPECT_EQ(a[k].deepest_vertex, b[k].deepest_vertex);
    EXPECT_TRUE(same_vec(a[k].deepest_point, b[k].deepest_point));
    EXPECT_TRUE(same_vec(a[k].nearest_point, b[k].nearest_point));
    EXPECT_EQ(a[k].inside_vertices, b[k].inside_vertices);
    EXPECT_EQ(a[k].overlapping_triangles, b[k].overlapping_triangles);
    EXPECT_EQ(a[k].reason, b[k].reason);
    EXPECT_EQ(a[k].reason_features, b[k].reason_features);
  }
}

}  // namespace vproxq::test
