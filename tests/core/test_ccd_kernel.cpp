// Tests of the elementary CCD tests (core/geometry/ccd.hpp) on cases with known answers:
// contact at t = 0 and t = 1, coplanar sliding, parallel and collinear edges, degenerate
// triangles and edges, no motion, near misses; plus seeded random queries constructed to
// collide at a known time (the reported TOI must not exceed it) or to stay apart.
#include <gtest/gtest.h>

#include "core/broad_phase/object_broad_phase.hpp"
#include "core/geometry/ccd.hpp"
#include "core/geometry/point_triangle.hpp"
#include "core/geometry/segment_segment.hpp"
#include "support/random_scene.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <array>
#include <cmath>

namespace vproxq {
namespace {

using P4 = std::array<Vec3, 4>;

// A static unit right triangle in the plane z = 0.
const Vec3 kA(0, 0, 0), kB(1, 0, 0), kC(0, 1, 0);

CcdResult vf_static_triangle(const Vec3& p0, const Vec3& p1) {
  return vertex_face_ccd(P4{p0, kA, kB, kC}, P4{p1, kA, kB, kC});
}

// A tolerance on TOIs: the finder stops at boxes whose image is within δ ~ 1e-6 * extent.
constexpr double kToiSlack = 1e-5;

// A query built to touch at t*: it must be reported, no later than t* (up to rounding of
// the construction). Counts the box-limit hits.
::testing::AssertionResult found_by(const CcdResult& r, double ts, int& limit_hits) {
  limit_hits += r.hit_limit;
  if (!r.collides) return ::testing::AssertionFailure() << "missed, t* " << ts;
  if (r.toi > ts + 1e-9) return ::testing::AssertionFailure() << "toi " << r.toi << " after t* " << ts;
  return ::testing::AssertionSuccess();
}

TEST(CcdKernel, VertexThroughTriangle) {
  const CcdResult r = vf_static_triangle({0.2, 0.2, 1}, {0.2, 0.2, -1});
  ASSERT_TRUE(r.collides);
  EXPECT_LE(r.toi, 0.5);
  EXPECT_GE(r.toi, 0.5 - kToiSlack);
  EXPECT_FALSE(r.hit_limit);
}

TEST(CcdKernel, VertexPassesBeside) {
  EXPECT_FALSE(vf_static_triangle({2, 2, 1}, {2, 2, -1}).collides);
  // Just outside the hypotenuse x + y = 1 (by 1e-3, far above δ).
  EXPECT_FALSE(vf_static_triangle({0.5005, 0.5005, 1}, {0.5005, 0.5005, -1}).collides);
  // Stops just before the plane.
  EXPECT_FALSE(vf_static_triangle({0.2, 0.2, 1}, {0.2, 0.2, 1e-3}).collides);
}

TEST(CcdKernel, VertexContactAtStart) {
  const CcdResult r = vf_static_triangle({0.2, 0.2, 0}, {0.2, 0.2, 1});
  ASSERT_TRUE(r.collides);
  EXPECT_EQ(r.toi, 0.0);
  // On a corner and on an edge of the triangle.
  EXPECT_TRUE(vf_static_triangle({1, 0, 0}, {3, 3, 3}).collides);
  EXPECT_TRUE(vf_static_triangle({0.5, 0.5, 0}, {3, 3, 3}).collides);
}

TEST(CcdKernel, VertexContactAtEnd) {
  const CcdResult r = vf_static_triangle({0.2, 0.2, 1}, {0.2, 0.2, 0});
  ASSERT_TRUE(r.collides);
  EXPECT_LE(r.toi, 1.0);
  EXPECT_GE(r.toi, 1.0 - kToiSlack);
  // Reaching a corner exactly at t = 1.
  EXPECT_TRUE(vf_static_triangle({0, 1, 1}, {0, 1, 0}).collides);
}

TEST(CcdKernel, CoplanarSliding) {
  // In the triangle's plane, entering the triangle at x = 0, i.e. t = 1/3.
  const CcdResult r = vf_static_triangle({-1, 0.2, 0}, {2, 0.2, 0});
  ASSERT_TRUE(r.collides);
  EXPECT_LE(r.toi, 1.0 / 3.0);
  EXPECT_GE(r.toi, 1.0 / 3.0 - kToiSlack);
  // In the plane, but passing outside it.
  EXPECT_FALSE(vf_static_triangle({-1, 2, 0}, {2, 2, 0}).collides);
}

TEST(CcdKernel, NoMotion) {
  EXPECT_TRUE(vf_static_triangle({0.3, 0.3, 0}, {0.3, 0.3, 0}).collides);
  EXPECT_FALSE(vf_static_triangle({0.3, 0.3, 0.1}, {0.3, 0.3, 0.1}).collides);
  const P4 e{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, -1, 0), Vec3(0.5, 1, 0)};
  EXPECT_TRUE(edge_edge_ccd(e, e).collides);
  const P4 f{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.5, -1, 0.1), Vec3(0.5, 1, 0.1)};
  EXPECT_FALSE(edge_edge_ccd(f, f).collides);
}

TEST(CcdKernel, BothMoving) {
  // The triangle rises from z = 0 to z = 1 while the vertex falls from 1 to 0: meet at 0.5.
  const Vec3 up(0, 0, 1);
  const CcdResult r = vertex_face_ccd(P4{Vec3(0.25, 0.25, 1), kA, kB, kC},
                                      P4{Vec3(0.25, 0.25, 0), kA + up, kB + up, kC + up});
  ASSERT_TRUE(r.collides);
  EXPECT_LE(r.toi, 0.5);
  EXPECT_GE(r.toi, 0.5 - kToiSlack);
  // Same motion, vertex moving with the triangle: never touch.
  EXPECT_FALSE(vertex_face_ccd(P4{Vec3(0.25, 0.25, 0.5), kA, kB, kC},
                               P4{Vec3(0.25, 0.25, 1.5), kA + up, kB + up, kC + up})
                   .collides);
}

TEST(CcdKernel, DegenerateTriangle) {
  // Collinear corners: the "triangle" is the segment [0, 2] on the x axis.
  const Vec3 a(0, 0, 0), b(1, 0, 0), c(2, 0, 0);
  EXPECT_TRUE(vertex_face_ccd(P4{Vec3(1.5, -1, 0), a, b, c}, P4{Vec3(1.5, 1, 0), a, b, c}).collides);
  EXPECT_FALSE(vertex_face_ccd(P4{Vec3(1.5, -1, 0.1), a, b, c}, P4{Vec3(1.5, 1, 0.1), a, b, c}).collides);
  EXPECT_FALSE(vertex_face_ccd(P4{Vec3(2.5, -1, 0), a, b, c}, P4{Vec3(2.5, 1, 0), a, b, c}).collides);
  // All three corners at one point: hit only through that point.
  const Vec3 o(1, 1, 1);
  EXPECT_TRUE(vertex_face_ccd(P4{Vec3(0, 0, 0), o, o, o}, P4{Vec3(2, 2, 2), o, o, o}).collides);
  EXPECT_FALSE(vertex_face_ccd(P4{Vec3(0, 0, 0.1), o, o, o}, P4{Vec3(2, 2, 2.1), o, o, o}).collides);
}

TEST(CcdKernel, CrossingEdges) {
  const Vec3 a0(0, 0, 0), a1(1, 0, 0);
  const CcdResult r = edge_edge_ccd(P4{a0, a1, Vec3(0.5, -1, 1), Vec3(0.5, 1, 1)},
                                    P4{a0, a1, Vec3(0.5, -1, -1), Vec3(0.5, 1, -1)});
  ASSERT_TRUE(r.collides);
  EXPECT_LE(r.toi, 0.5);
  EXPECT_GE(r.toi, 0.5 - kToiSlack);
  // Passing beyond the end of edge a.
  EXPECT_FALSE(edge_edge_ccd(P4{a0, a1, Vec3(1.5, -1, 1), Vec3(1.5, 1, 1)},
                             P4{a0, a1, Vec3(1.5, -1, -1), Vec3(1.5, 1, -1)})
                   .collides);
}

TEST(CcdKernel, ParallelEdges) {
  const Vec3 a0(0, 0, 0), a1(1, 0, 0);
  // Parallel, overlapping in x in [0.5, 1], dropping through: contact at t = 0.5.
  const CcdResult r = edge_edge_ccd(P4{a0, a1, Vec3(0.5, 0, 1), Vec3(1.5, 0, 1)},
                                    P4{a0, a1, Vec3(0.5, 0, -1), Vec3(1.5, 0, -1)});
  ASSERT_TRUE(r.collides);
  EXPECT_LE(r.toi, 0.5);
  EXPECT_GE(r.toi, 0.5 - kToiSlack);
  // Parallel, offset by 0.1 in y: never touch.
  EXPECT_FALSE(edge_edge_ccd(P4{a0, a1, Vec3(0.5, 0.1, 1), Vec3(1.5, 0.1, 1)},
                             P4{a0, a1, Vec3(0.5, 0.1, -1), Vec3(1.5, 0.1, -1)})
                   .collides);
  // Collinear, sliding toward each other along the x axis: touch when b0 reaches a1 (t = 0.5).
  const CcdResult s = edge_edge_ccd(P4{a0, a1, Vec3(2, 0, 0), Vec3(3, 0, 0)},
                                    P4{a0, a1, Vec3(0, 0, 0), Vec3(1, 0, 0)});
  ASSERT_TRUE(s.collides);
  EXPECT_LE(s.toi, 0.5);
  EXPECT_GE(s.toi, 0.5 - kToiSlack);
}

TEST(CcdKernel, EdgeContactAtEnds) {
  const Vec3 a0(0, 0, 0), a1(1, 0, 0);
  // Touching at t = 0 (b0 on a), then leaving.
  const CcdResult r0 = edge_edge_ccd(P4{a0, a1, Vec3(0.5, 0, 0), Vec3(0.5, 1, 0)},
                                     P4{a0, a1, Vec3(0.5, 0, 1), Vec3(0.5, 1, 1)});
  ASSERT_TRUE(r0.collides);
  EXPECT_EQ(r0.toi, 0.0);
  // Arriving exactly at t = 1.
  const CcdResult r1 = edge_edge_ccd(P4{a0, a1, Vec3(0.5, -1, 1), Vec3(0.5, 1, 1)},
                                     P4{a0, a1, Vec3(0.5, -1, 0), Vec3(0.5, 1, 0)});
  ASSERT_TRUE(r1.collides);
  EXPECT_GE(r1.toi, 1.0 - kToiSlack);
  // Endpoint to endpoint at t = 1.
  EXPECT_TRUE(edge_edge_ccd(P4{a0, a1, Vec3(2, 1, 0), Vec3(3, 1, 0)},
                            P4{a0, a1, Vec3(1, 0, 0), Vec3(2, 0, 0)})
                  .collides);
}

TEST(CcdKernel, DegenerateEdge) {
  const Vec3 a0(0, 0, 0), a1(1, 0, 0);
  // Edge b is a single point passing through edge a, and beside it.
  EXPECT_TRUE(edge_edge_ccd(P4{a0, a1, Vec3(0.3, 0, 1), Vec3(0.3, 0, 1)},
                            P4{a0, a1, Vec3(0.3, 0, -1), Vec3(0.3, 0, -1)})
                  .collides);
  EXPECT_FALSE(edge_edge_ccd(P4{a0, a1, Vec3(0.3, 0.01, 1), Vec3(0.3, 0.01, 1)},
                             P4{a0, a1, Vec3(0.3, 0.01, -1), Vec3(0.3, 0.01, -1)})
                   .collides);
}

// Near-degenerate queries, in a rotated frame so that no coordinate axis separates them: the
// coordinate ranges of F straddle 0 until the parameter boxes are tiny, and only the
// directional exclusion (ccd.cpp) keeps these within a few thousand boxes. Each of them ran
// to the box limit (2^17) without it, on the breaking and cloth-funnel benchmark scenes.
TEST(CcdKernel, NearDegenerateQueriesAreDecidedWellBeforeTheBoxLimit) {
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.7, Vec3(1, 2, 3).normalized()).toRotationMatrix();
  auto rotated = [&](P4 p) {
    for (Vec3& x : p) x = rot * x + Vec3(0.3, -0.2, 0.1);
    return p;
  };
  constexpr std::uint32_t kFewBoxes = 10000;

  // Two edges that come from opposite sides and coincide exactly at t = 1 (fractured pieces
  // meeting along a shared edge): a line of roots at t = 1, none before.
  const P4 meet{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0, 0, 0), Vec3(1, 0, 0)};
  const CcdResult c = edge_edge_ccd(rotated(P4{Vec3(0, 0.5, 2), Vec3(1, 0.8, 2.5), Vec3(0.2, -1, -2), Vec3(1.3, -0.6, -1)}),
                                    rotated(meet));
  ASSERT_TRUE(c.collides);
  EXPECT_LE(c.toi, 1.0);
  EXPECT_GE(c.toi, 1.0 - kToiSlack);
  EXPECT_FALSE(c.hit_limit);
  EXPECT_LT(c.boxes, kFewBoxes);

  // Nearly parallel edges (angle 1e-4) passing each other 5e-5 apart (about 30 δ): no contact.
  const CcdResult p = edge_edge_ccd(rotated(P4{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(-0.3, 5e-5, 0.6), Vec3(0.7, 5e-5, 0.6001)}),
                                    rotated(P4{Vec3(0, 0, 0), Vec3(1, 0, 0), Vec3(0.3, 5e-5, -0.6), Vec3(1.3, 5e-5, -0.5999)}));
  EXPECT_FALSE(p.collides);
  EXPECT_FALSE(p.hit_limit);
  EXPECT_LT(p.boxes, kFewBoxes);

  // A vertex sliding across a face 1e-4 above it (far above δ ~ 1e-6): no contact.
  const Vec3 a(0, 0, 0), b(1, 0, 0), cc(0, 1, 0);
  const CcdResult v = vertex_face_ccd(rotated(P4{Vec3(-0.5, 0.2, 1e-4), a, b, cc}), rotated(P4{Vec3(1.5, 0.3, 1e-4), a, b, cc}));
  EXPECT_FALSE(v.collides);
  EXPECT_FALSE(v.hit_limit);
  EXPECT_LT(v.boxes, kFewBoxes);
}

// A vertex in line with a degenerate triangle (two corners at one point, the third apart):
// F keeps one direction, so beyond the hypotenuse u + v = 1 it vanishes on a whole surface of
// (t, u, v) that lies outside the triangle. Boxes across the hypotenuse must be judged by their
// part inside it; judged by their corners, the contact at t = 1 below stopped at the box limit
// and was reported at t = 0.4995 (found by fuzzing, tests/fuzz/fuzz_queries.cpp).
TEST(CcdKernel, AVertexInLineWithADegenerateTriangleIsJudgedWithinTheTriangle) {
  const Eigen::Matrix3d rot = Eigen::AngleAxisd(0.4, Vec3(3, -1, 2).normalized()).toRotationMatrix();
  constexpr std::uint32_t kFewBoxes = 10000;
  const Vec3 diag(1, 1, 1);
  for (bool rotate : {false, true}) {
    SCOPED_TRACE(rotate ? "rotated" : "on the diagonal");
    auto frame = [&](P4 p) {
      if (rotate)
        for (Vec3& x : p) x = rot * x + Vec3(0.3, -0.2, 0.1);
      return p;
    };
    // p and a fixed, b = c moving from a to p: the closed triangle reaches p at t = 1 only.
    const Vec3 p = -8 * diag, a = 3.5 * diag;
    const CcdResult end = vertex_face_ccd(frame(P4{p, a, a, a}), frame(P4{p, a, p, p}));
    ASSERT_TRUE(end.collides);
    EXPECT_LE(end.toi, 1.0);
    EXPECT_GE(end.toi, 1.0 - kToiSlack);
    EXPECT_FALSE(end.hit_limit);
    EXPECT_LT(end.boxes, kFewBoxes);
    // b = c stops 1e-3 of the way short of p (far beyond δ): no contact.
    const Vec3 short_of_p = p + 1e-3 * (a - p);
    const CcdResult miss = vertex_face_ccd(frame(P4{p, a, a, a}), frame(P4{p, a, short_of_p, short_of_p}));
    EXPECT_FALSE(miss.collides);
    EXPECT_FALSE(miss.hit_limit);
    EXPECT_LT(miss.boxes, kFewBoxes);
    // The vertex moving along the line onto the fixed segment [a, b]: contact at t = 0.5.
    const Vec3 b = -2 * diag;
    const CcdResult mid = vertex_face_ccd(frame(P4{-6 * diag, a, b, b}), frame(P4{2 * diag, a, b, b}));
    ASSERT_TRUE(mid.collides);
    EXPECT_LE(mid.toi, 0.5 + 1e-12);
    EXPECT_GE(mid.toi, 0.5 - kToiSlack);
    EXPECT_FALSE(mid.hit_limit);
    EXPECT_LT(mid.boxes, kFewBoxes);
  }
}

// A vertex that slides along the triangle's edge bc, in the triangle's plane: the roots lie on
// the hypotenuse u + v = 1 itself (F's component off the line bc is (p - a) (1 - u - v)), and
// the first contact is at corner c or b. The earliest-face certificate must look just inside
// the hypotenuse, not on it: from (u, v) = (0, 1) alone it certified nothing, and the first
// query below (found by tests/fuzz/fuzz_ccd_kernel.cpp) stopped at the box limit. The triangle
// grows from a point; b and c move along the line, a off it; everything is exact, so the
// contact interval is exactly [0.5, 0.75] (c reaches p at 0.5, b at 0.75).
TEST(CcdKernel, AVertexSlidingAlongAnEdgeMeetsItsCornerFirst) {
  constexpr std::uint32_t kFewBoxes = 10000;
  const Vec3 o(-8, 0, -8);
  const P4 start{Vec3(-5, 0, -8), o, o, o};
  const P4 end{Vec3(2, 0, -8), Vec3(-8, 0, 5), Vec3(3, 0, -8), Vec3(5, 0, -8)};
  auto expect_contact_at = [&](const CcdResult& r, double toi) {
    ASSERT_TRUE(r.collides);
    EXPECT_LE(r.toi, toi);
    EXPECT_GE(r.toi, toi - kToiSlack);
    EXPECT_FALSE(r.hit_limit);
    EXPECT_LT(r.boxes, kFewBoxes);
  };
  {
    SCOPED_TRACE("meets c first");
    expect_contact_at(vertex_face_ccd(start, end), 0.5);
  }
  {
    SCOPED_TRACE("time reversed: meets b first");
    expect_contact_at(vertex_face_ccd(end, start), 0.25);
  }
  {
    SCOPED_TRACE("b and c swapped");
    expect_contact_at(vertex_face_ccd(P4{start[0], start[1], start[3], start[2]}, P4{end[0], end[1], end[3], end[2]}), 0.5);
  }
}

// The directional exclusion must never remove a root: random queries that touch at a chosen
// time t* in the configurations it is meant for, all in a random rotated frame: coplanar
// vertex–face motion (everything in one plane), coplanar crossing edges, and collinear edges
// (everything on one line). As in RandomCollidingQueries, the positions at t* coincide up to
// rounding, so the answer must be "collides" with toi <= t*.
TEST(CcdKernel, RandomDegenerateCollidingQueries) {
  test::Rng rng(4242);
  int limit_hits = 0;
  for (int q = 0; q < 3000; ++q) {
    const int kind = q % 3;  // 0: coplanar vertex-face, 1: coplanar edges, 2: collinear edges
    const double ts = q % 10 == 0 ? 0.0 : q % 10 == 1 ? 1.0 : rng.uniform(0, 1);
    // Points in the plane z = 0 (kind 0, 1) or on the x axis (kind 2).
    auto rnd = [&] { return Vec3{rng.uniform(-1, 1), kind == 2 ? 0.0 : rng.uniform(-1, 1), 0.0}; };
    P4 s{rnd(), rnd(), rnd(), rnd()}, e{rnd(), rnd(), rnd(), rnd()};
    auto at = [&](int i) { return Vec3(s[static_cast<size_t>(i)] + ts * (e[static_cast<size_t>(i)] - s[static_cast<size_t>(i)])); };
    double u = rng.uniform(0, 1), v = rng.uniform(0, 1);
    if (kind == 0 && u + v > 1) {
      u = 1 - u;
      v = 1 - v;
    }
    Vec3 shift;
    if (kind == 0) {
      shift = at(1) + u * (at(2) - at(1)) + v * (at(3) - at(1)) - at(0);
    } else {
      shift = at(2) + v * (at(3) - at(2)) - (at(0) + u * (at(1) - at(0)));
    }
    for (int i = 0; i < (kind == 0 ? 1 : 2); ++i) {
      s[static_cast<size_t>(i)] += shift;
      e[static_cast<size_t>(i)] += shift;
    }
    const Eigen::Matrix3d rot =
        Eigen::AngleAxisd{rng.uniform(0, 3), rng.vec3(-1, 1).normalized()}.toRotationMatrix();
    for (P4* p : {&s, &e})
      for (Vec3& x : *p) x = rot * x;
    ASSERT_TRUE(found_by(kind == 0 ? vertex_face_ccd(s, e) : edge_edge_ccd(s, e), ts, limit_hits))
        << "query " << q << " kind " << kind;
  }
  std::printf("[          ] degenerate colliding queries: 3000, box-limit hits: %d\n", limit_hits);
}

// Two layers of a rolled sheet that turn together during the step, as the turns of a cloth
// roll do: layer a at radius r, layer b at radius r + gap (the gap shrinking by 30% over the
// step), both turned by omega about the roll's axis (the z axis, before a random rotation of
// everything). Edge–edge: a chord of each layer spanning the same angles, or an axial edge of
// each (the same angle, z from 0 to h). Vertex–face: a vertex of layer b over a face of
// layer a. The points move linearly from their start to their end positions (what the kernel
// assumes), so the layers' edges stay parallel or nearly so all along the step.
struct RollPair {
  P4 start, end;
};

RollPair roll_pair(test::Rng& rng, bool vf, double gap_over_edge) {
  const double r = rng.uniform(0.3, 1), arc = rng.uniform(0.05, 0.4), h = rng.uniform(0.05, 0.4);
  const double theta = rng.uniform(0, 6.3), omega = rng.uniform(-0.5, 0.5), lag = rng.uniform(-0.1, 0.1) * arc;
  const double gap = gap_over_edge * arc * r;
  const bool axial = rng.uniform(0, 1) < 0.5;
  auto point = [&](double radius, double angle, double z) { return Vec3(radius * std::cos(angle), radius * std::sin(angle), z); };
  RollPair p;
  for (int end = 0; end < 2; ++end) {
    const double turn = theta + omega * end, rb = r + gap * (1 - 0.3 * end);
    P4& x = end ? p.end : p.start;
    if (vf) {
      x[0] = point(rb, turn + lag + 0.3 * arc, 0.4 * h);
      x[1] = point(r, turn, 0);
      x[2] = point(r, turn + arc, 0);
      x[3] = point(r, turn, h);
    } else if (axial) {
      x[0] = point(r, turn, 0);
      x[1] = point(r, turn, h);
      x[2] = point(rb, turn + lag, 0);
      x[3] = point(rb, turn + lag, h);
    } else {
      x[0] = point(r, turn, 0);
      x[1] = point(r, turn + arc, 0);
      x[2] = point(rb, turn + lag, 0);
      x[3] = point(rb, turn + lag + arc, 0);
    }
  }
  const Eigen::Matrix3d rot =
      Eigen::AngleAxisd{rng.uniform(0, 3), rng.vec3(-1, 1).normalized()}.toRotationMatrix();
  for (P4* x : {&p.start, &p.end})
    for (Vec3& y : *x) y = rot * y;
  return p;
}

// The moving-direction exclusion (ccd.cpp) must never remove a root: rolled layers (above)
// moved so that they touch at a chosen time t*, as in RandomCollidingQueries: the vertex, or
// edge b, is translated so that its point at t* coincides with a point of the face or of
// edge a (up to rounding).
TEST(CcdKernel, TurningLayersThatTouchAreFound) {
  test::Rng rng(777);
  int limit_hits = 0;
  for (int q = 0; q < 4000; ++q) {
    const bool vf = q % 2 == 0;
    RollPair p = roll_pair(rng, vf, std::pow(10.0, rng.uniform(-9, -1)));
    const double ts = q % 10 == 0 ? 0.0 : q % 10 == 1 ? 1.0 : rng.uniform(0, 1);
    auto at = [&](int i) {
      return Vec3(p.start[static_cast<size_t>(i)] + ts * (p.end[static_cast<size_t>(i)] - p.start[static_cast<size_t>(i)]));
    };
    double u = rng.uniform(0, 1), v = rng.uniform(0, 1);
    Vec3 shift;
    if (vf) {
      if (u + v > 1) {
        u = 1 - u;
        v = 1 - v;
      }
      shift = at(1) + u * (at(2) - at(1)) + v * (at(3) - at(1)) - at(0);
    } else {
      if (q % 4 == 1) v = std::clamp(u + rng.uniform(-1e-3, 1e-3), 0.0, 1.0);  // the matching points of the two edges
      shift = at(0) + u * (at(1) - at(0)) - (at(2) + v * (at(3) - at(2)));
    }
    for (int i = vf ? 0 : 2; i < (vf ? 1 : 4); ++i) {
      p.start[static_cast<size_t>(i)] += shift;
      p.end[static_cast<size_t>(i)] += shift;
    }
    ASSERT_TRUE(found_by(vf ? vertex_face_ccd(p.start, p.end) : edge_edge_ccd(p.start, p.end), ts, limit_hits))
        << "query " << q;
  }
  std::printf("[          ] touching turning layers: 4000, box-limit hits: %d\n", limit_hits);
}

// The same layers 1e-7 to 1e-5 of an edge apart and not touching: edges of a roll's adjacent
// turns. With one fixed direction per box, these ran to the box limit (2^17) at gaps up to
// 2e-6 (a 288-triangle roll: 360 edge pairs, 5 s per step); a direction that turns with t
// decides them in a few hundred boxes.
TEST(CcdKernel, TurningLayersApartAreDecidedInFewBoxes) {
  test::Rng rng(778);
  std::uint64_t boxes = 0;
  std::uint32_t most = 0;
  for (int q = 0; q < 2000; ++q) {
    const RollPair p = roll_pair(rng, q % 2 == 0, std::pow(10.0, rng.uniform(-7, -5)));
    const CcdResult r = q % 2 == 0 ? vertex_face_ccd(p.start, p.end) : edge_edge_ccd(p.start, p.end);
    EXPECT_FALSE(r.hit_limit) << "query " << q;
    boxes += r.boxes;
    most = std::max(most, r.boxes);
  }
  std::printf("[          ] turning layers apart: 2000, boxes: %llu, most in one query: %u\n",
              static_cast<unsigned long long>(boxes), most);
  EXPECT_LT(most, 20000u);
}

TEST(CcdKernel, NonFiniteInputIsConservative) {
  const double nan = std::numeric_limits<double>::quiet_NaN();
  const CcdResult r = vf_static_triangle({nan, 0, 0}, {0, 0, 0});
  EXPECT_TRUE(r.collides);
  EXPECT_EQ(r.toi, 0.0);
}

// Random queries that collide at a chosen time t*: positions at t* are made to coincide (up
// to rounding, far below δ), so the answer must be "collides" with toi <= t* (+ rounding).
TEST(CcdKernel, RandomCollidingQueries) {
  test::Rng rng(20240611);
  auto rnd = [&] { return rng.vec3(-1, 1); };
  int limit_hits = 0;
  for (int q = 0; q < 2000; ++q) {
    const int tcase = q % 10;
    const double ts = tcase == 0 ? 0.0 : tcase == 1 ? 1.0 : rng.uniform(0, 1);
    P4 s{rnd(), rnd(), rnd(), rnd()}, e{rnd(), rnd(), rnd(), rnd()};
    const bool vf = q % 2 == 0;
    double u = rng.uniform(0, 1), v = rng.uniform(0, 1);
    if (vf && u + v > 1) {
      u = 1 - u;
      v = 1 - v;
    }
    auto at = [&](int i) { return Vec3(s[static_cast<size_t>(i)] + ts * (e[static_cast<size_t>(i)] - s[static_cast<size_t>(i)])); };
    // Move point 0 (the vertex, or a0 with a1 translated along) so it meets the target at ts.
    Vec3 target;
    if (vf) {
      target = at(1) + u * (at(2) - at(1)) + v * (at(3) - at(1));
    } else {
      target = at(2) + v * (at(3) - at(2));  // a point of edge b at ts
    }
    // Choose point 0's position at ts to be target (edge–edge: a's point at parameter u).
    const Vec3 shift = vf ? Vec3(target - at(0)) : Vec3(target - (at(0) + u * (at(1) - at(0))));
    s[0] += shift;
    e[0] += shift;
    if (!vf) {
      s[1] += shift;
      e[1] += shift;
    }
    ASSERT_TRUE(found_by(vf ? vertex_face_ccd(s, e) : edge_edge_ccd(s, e), ts, limit_hits)) << "query " << q;
  }
  std::printf("[          ] random colliding queries: 2000, box-limit hits: %d\n", limit_hits);
}

// A hit certifies that the primitives come within δ_k on every axis at the reported TOI (the
// whole box within δ, or one point of its earliest face: ccd.cpp), so their distance at the TOI
// is at most sqrt(3) max δ_k. The pipeline's culling margins rely on this (a pair apart by more
// is never reported). Queries built to touch at a random time, and near misses: the same
// contact at t = 0, held apart by 0.2 to 3 δ along the normal there while all four points move
// by one common motion (so the distance stays that gap throughout; the directional test decides
// these apart, so none is reported now, and any that were would have to meet the bound).
TEST(CcdKernel, AReportedToiIsATimeWhenThePrimitivesAreWithinTolerance) {
  test::Rng rng(5150);
  auto rnd = [&] { return rng.vec3(-1, 1); };
  int reported = 0, near_misses = 0, near_misses_reported = 0;
  for (int q = 0; q < 4000; ++q) {
    const bool vf = q % 2 == 0;
    const bool near_miss = q % 4 >= 2;
    const double ts = near_miss || q % 10 == 0 ? 0.0 : rng.uniform(0, 1);
    P4 s{rnd(), rnd(), rnd(), rnd()}, e{rnd(), rnd(), rnd(), rnd()};
    if (near_miss) {
      const Vec3 motion = rnd();
      for (size_t i = 0; i < 4; ++i) e[i] = s[i] + motion;
    }
    double u = rng.uniform(0.05, 0.95), v = rng.uniform(0.05, 0.95);
    if (vf && u + v > 0.95) {
      u = 0.95 - u;
      v = 0.95 - v;
    }
    auto at = [&](int i, double t) {
      return Vec3(s[static_cast<size_t>(i)] + t * (e[static_cast<size_t>(i)] - s[static_cast<size_t>(i)]));
    };
    const Vec3 target = vf ? Vec3(at(1, ts) + u * (at(2, ts) - at(1, ts)) + v * (at(3, ts) - at(1, ts)))
                           : Vec3(at(2, ts) + v * (at(3, ts) - at(2, ts)));
    Vec3 shift = vf ? Vec3(target - at(0, ts)) : Vec3(target - (at(0, ts) + u * (at(1, ts) - at(0, ts))));
    double gap = 0;
    if (near_miss) {
      const Vec3 n = vf ? Vec3((at(2, 0) - at(1, 0)).cross(at(3, 0) - at(1, 0))) : Vec3((at(1, 0) - at(0, 0)).cross(at(3, 0) - at(2, 0)));
      if (!(n.norm() > 1e-2)) continue;
      gap = rng.uniform(0.2, 3) * 2e-6;  // δ is 1e-6 of an extent of about 2
      shift += gap * n.normalized();
      ++near_misses;
    }
    for (int i = 0; i < (vf ? 1 : 2); ++i) {
      s[static_cast<size_t>(i)] += shift;
      e[static_cast<size_t>(i)] += shift;
    }
    const CcdResult r = vf ? vertex_face_ccd(s, e) : edge_edge_ccd(s, e);
    if (!near_miss) {
      ASSERT_TRUE(r.collides) << "query " << q;
    }
    if (!r.collides || r.hit_limit) continue;
    ++reported;
    near_misses_reported += near_miss;
    AABB box;
    box.lo = box.hi = s[0];
    double magnitude = 0;
    for (const P4* p : {&s, &e})
      for (const Vec3& x : *p) {
        box.extend(x);
        magnitude = std::max(magnitude, x.cwiseAbs().maxCoeff());
      }
    const double bound = std::sqrt(3.0) * ccd_max_tolerance((box.hi - box.lo).maxCoeff(), magnitude) * (1 + 1e-6);
    const double t = r.toi;
    const double d2 = vf ? point_triangle_distance(at(0, t), Triangle{at(1, t), at(2, t), at(3, t)}).squared_distance
                         : segment_segment_distance(at(0, t), at(1, t), at(2, t), at(3, t)).squared_distance;
    ASSERT_LE(std::sqrt(d2), bound) << "query " << q << (vf ? " vf" : " ee") << ", gap " << gap << ", toi " << t;
  }
  std::printf("[          ] reported: %d (near misses: %d of %d)\n", reported, near_misses_reported, near_misses);
}

// Random queries kept apart: the vertex / edge b stay above z = 0.1 while the triangle / edge a
// stay below z = 0: never a collision, and with a gap of 0.1 not even a near miss.
TEST(CcdKernel, RandomSeparatedQueries) {
  test::Rng rng(77);
  auto below = [&] { return Vec3{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(-1, 0)}; };
  auto above = [&] { return Vec3{rng.uniform(-1, 1), rng.uniform(-1, 1), rng.uniform(0.1, 1)}; };
  for (int q = 0; q < 2000; ++q) {
    if (q % 2 == 0) {
      const P4 s{above(), below(), below(), below()}, e{above(), below(), below(), below()};
      ASSERT_FALSE(vertex_face_ccd(s, e).collides) << q;
    } else {
      const P4 s{below(), below(), above(), above()}, e{below(), below(), above(), above()};
      ASSERT_FALSE(edge_edge_ccd(s, e).collides) << q;
    }
  }
}

TEST(CcdKernel, SharesOfTwoPointSetsCoverTheirPairsTolerance) {
  // For boxes A and B at most M apart, M = ccd_max_tolerance(extent of both, max magnitude) +
  // rounding_slack(max magnitude): each box widened by its own share covers M.
  test::Rng rng(41);
  int close = 0;
  for (int k = 0; k < 20000; ++k) {
    const double scale = std::pow(10.0, rng.uniform(-8, 8));
    const double power = std::pow(10.0, rng.uniform(-8, 12));
    const double offset = power * (rng.uniform(0, 1) < 0.5 ? -1 : 1);
    auto box = [&](AABB& b) {
      const Vec3 lo = Vec3::Constant(offset) + scale * rng.vec3(-1, 1);
      b.lo = lo;
      const double size = rng.uniform(0, 1);
      b.hi = lo + scale * size * rng.vec3(0, 1);
    };
    AABB a, b;
    box(a);
    box(b);
    auto magnitude = [](const AABB& x) { return std::max(x.lo.cwiseAbs().maxCoeff(), x.hi.cwiseAbs().maxCoeff()); };
    AABB both = a;
    both.extend(b);
    const double m = std::max(magnitude(a), magnitude(b));
    const double pair = ccd_max_tolerance((both.hi - both.lo).maxCoeff(), m) + rounding_slack(m);
    const double gap = (a.lo - b.hi).cwiseMax(b.lo - a.hi).maxCoeff();
    if (gap > pair) continue;  // the pair's own margin already culls them
    ++close;
    auto share = [&](const AABB& x) {
      return ccd_tolerance_share((x.hi - x.lo).maxCoeff(), magnitude(x)) + rounding_slack(magnitude(x)) * ccd_share_factor();
    };
    ASSERT_GE(share(a) + share(b), pair) << "scale " << scale << " offset " << offset;
  }
  EXPECT_GT(close, 1000);
}

}  // namespace
}  // namespace vproxq
