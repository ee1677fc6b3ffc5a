// Local penetration depth (paper 3.3) against analytic truth: overlapping axis-aligned boxes
// (depth d along the overlap axis), overlapping icospheres (depth within the stated sampling
// error of r1 + r2 - |c1 - c2|), the exact inside test, and the statuses where PD is undefined;
// self-intersecting objects against analytic depths and against the same geometry as
// separate objects (the inter-object twin).
#include "core/query/intersecting_pairs.hpp"
#include "core/geometry/exact_distance.hpp"
#include "core/geometry/predicates.hpp"
#include "core/geometry/point_triangle.hpp"
#include "core/geometry/triangle_intersection.hpp"
#include "core/mesh/adjacency.hpp"
#include "core/query/penetration_depth.hpp"
#include "support/pd_checks.hpp"
#include "support/random_scene.hpp"
#include "support/rng.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <map>

namespace vproxq {
namespace {

/// The box [lo, lo + size] with counts[k] cells along axis k, every face cut into a grid of
/// quads (2 triangles each), vertices shared along the box's edges: faces oriented outwards.
/// The cell (i, j) of the face (axis, side) listed in `hole` is left open, and its four
/// corners (in the face's cyclic order) are returned in `hole_ring`; without a hole the box
/// is closed.
struct HoledBox {
  Object object;
  std::array<Index, 4> hole_ring{kNoIndex, kNoIndex, kNoIndex, kNoIndex};
};
HoledBox make_grid_box(const Vec3& lo, const Vec3& size, std::array<int, 3> counts,
                       std::array<int, 4> hole = {-1, -1, -1, -1}) {
  std::map<std::array<int, 3>, Index> ids;
  HoledBox out;
  Object& o = out.object;
  auto topo = std::make_shared<Topology>();
  auto vertex = [&](std::array<int, 3> g) {
    auto it = ids.find(g);
    if (it != ids.end()) return it->second;
    const Index id = static_cast<Index>(o.positions.size());
    Vec3 p;
    for (int k = 0; k < 3; ++k)
      p[k] = lo[k] + size[k] * (static_cast<double>(g[static_cast<size_t>(k)]) / counts[static_cast<size_t>(k)]);
    o.positions.push_back(p);
    ids[g] = id;
    return id;
  };
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, v = (axis + 2) % 3;
      for (int i = 0; i < counts[static_cast<size_t>(u)]; ++i)
        for (int j = 0; j < counts[static_cast<size_t>(v)]; ++j) {
          auto corner = [&](int di, int dj) {
            std::array<int, 3> g{};
            g[static_cast<size_t>(axis)] = side * counts[static_cast<size_t>(axis)];
            g[static_cast<size_t>(u)] = i + di;
            g[static_cast<size_t>(v)] = j + dj;
            return vertex(g);
          };
          const Index a = corner(0, 0), b = corner(1, 0), c = corner(1, 1), d = corner(0, 1);
          if (hole == std::array<int, 4>{axis, side, i, j}) {
            out.hole_ring = {a, b, c, d};
            continue;
          }
          if (side == 1) {
            topo->faces.push_back({a, b, c});
            topo->faces.push_back({a, c, d});
          } else {
            topo->faces.push_back({a, c, b});
            topo->faces.push_back({a, d, c});
          }
        }
    }
  topo->num_vertices = static_cast<Index>(o.positions.size());
  o.topology = topo;
  o.name = "box";
  return out;
}

/// make_grid_box with n cells along every axis, closed.
Object make_box(const Vec3& lo, const Vec3& size, int n, const std::string& name) {
  Object o = make_grid_box(lo, size, {n, n, n}).object;
  o.name = name;
  return o;
}

/// An icosahedron subdivided `levels` times (midpoints pushed onto the sphere): 20 * 4^levels
/// triangles, every vertex on the sphere of radius r around c, faces oriented outwards.
Object make_icosphere(const Vec3& c, double r, int levels, const std::string& name) {
  const double t = (1.0 + std::sqrt(5.0)) / 2.0;
  std::vector<Vec3> v = {{-1, t, 0}, {1, t, 0}, {-1, -t, 0}, {1, -t, 0}, {0, -1, t}, {0, 1, t},
                         {0, -1, -t}, {0, 1, -t}, {t, 0, -1}, {t, 0, 1}, {-t, 0, -1}, {-t, 0, 1}};
  for (Vec3& p : v) p.normalize();
  std::vector<Face> f = {{0, 11, 5}, {0, 5, 1}, {0, 1, 7}, {0, 7, 10}, {0, 10, 11},
                         {1, 5, 9}, {5, 11, 4}, {11, 10, 2}, {10, 7, 6}, {7, 1, 8},
                         {3, 9, 4}, {3, 4, 2}, {3, 2, 6}, {3, 6, 8}, {3, 8, 9},
                         {4, 9, 5}, {2, 4, 11}, {6, 2, 10}, {8, 6, 7}, {9, 8, 1}};
  for (int l = 0; l < levels; ++l) {
    std::map<std::pair<Index, Index>, Index> mid;
    auto midpoint = [&](Index a, Index b) {
      const auto key = std::minmax(a, b);
      auto it = mid.find({key.first, key.second});
      if (it != mid.end()) return it->second;
      v.push_back((v[static_cast<size_t>(a)] + v[static_cast<size_t>(b)]).normalized());
      const Index id = static_cast<Index>(v.size() - 1);
      mid[{key.first, key.second}] = id;
      return id;
    };
    std::vector<Face> nf;
    for (const Face& q : f) {
      const Index a = midpoint(q[0], q[1]), b = midpoint(q[1], q[2]), cc = midpoint(q[2], q[0]);
      nf.push_back({q[0], a, cc});
      nf.push_back({q[1], b, a});
      nf.push_back({q[2], cc, b});
      nf.push_back({a, b, cc});
    }
    f = std::move(nf);
  }
  Object o;
  auto topo = std::make_shared<Topology>();
  topo->num_vertices = static_cast<Index>(v.size());
  topo->faces = f;
  o.topology = topo;
  o.name = name;
  for (const Vec3& p : v) o.positions.push_back(c + r * p);
  return o;
}

Frame frame_of(std::vector<Object> objects) {
  Frame frame;
  frame.objects = std::move(objects);
  return frame;
}

std::vector<PenetrationDepth> run_pd(const Frame& frame, int threads = 2) {
  const FrameBoxes boxes = FrameBoxes::compute(frame, threads);
  const auto pairs = intersecting_pairs(frame, boxes, {threads, nullptr, true});
  return penetration_depth(frame, boxes, pairs.pairs, {threads}).pairs;
}

Vec3 axis_vector(int axis, double s = 1.0) {
  Vec3 e = Vec3::Zero();
  e[axis] = s;
  return e;
}

TEST(PenetrationDepth, WindingNumberIsExactOnDegenerateRays) {
  // Rays from points on the grid lines of a subdivided box pass exactly through its vertices
  // and edges: the perturbed count must still be 1 inside, 0 outside, and points on a face
  // not parallel to the ray are reported on the surface.
  const Object box = make_box(Vec3(0, 0, 0), Vec3(1, 1, 1), 4, "box");
  Object flipped = box;
  auto topo = std::make_shared<Topology>(*box.topology);
  for (Face& f : topo->faces) std::swap(f[1], f[2]);
  flipped.topology = topo;
  int inside = 0, outside = 0, on = 0;
  for (int i = -2; i <= 10; ++i)
    for (int j = -2; j <= 10; ++j)
      for (int k = -2; k <= 10; ++k) {
        const Vec3 p(0.125 * i, 0.125 * j, 0.125 * k);
        bool on_surface = false;
        const int w = winding_number_brute_force(p, box, on_surface);
        bool on_flipped = false;
        const int wf = winding_number_brute_force(p, flipped, on_flipped);
        EXPECT_EQ(on_surface, on_flipped);
        auto strictly = [](double x) { return x > 0 && x < 1; };
        auto closed = [](double x) { return x >= 0 && x <= 1; };
        const bool in_open = strictly(p.x()) && strictly(p.y()) && strictly(p.z());
        const bool in_closed = closed(p.x()) && closed(p.y()) && closed(p.z());
        SCOPED_TRACE("p = " + std::to_string(p.x()) + "," + std::to_string(p.y()) + "," + std::to_string(p.z()));
        if (in_open) {
          EXPECT_FALSE(on_surface);
          EXPECT_EQ(w, 1);
          EXPECT_EQ(wf, -1);
          ++inside;
        } else if (!in_closed) {
          EXPECT_FALSE(on_surface);
          EXPECT_EQ(w, 0);
          EXPECT_EQ(wf, 0);
          ++outside;
        } else {
          // On the boundary, on any face: those parallel to the ray (y or z = 0 or 1) too,
          // where the perturbed ray from p + (0, e, e^2) would see a point inside for
          // y = 0 or z = 0.
          EXPECT_TRUE(on_surface);
          EXPECT_EQ(w, 0);
          ++on;
        }
      }
  EXPECT_GT(inside, 300);
  EXPECT_GT(outside, 1000);
  EXPECT_GT(on, 100);
}

TEST(PenetrationDepth, OverlappingBoxesGiveDepthDAlongTheAxis) {
  // Unit boxes [0,1]^3 and [0,1]^3 + (1-d) e_axis: faces lying on each other, vertices on
  // the other's faces and edges. The overlap is d thick along the axis; A must move -axis.
  for (int n : {1, 4}) {
    for (int axis = 0; axis < 3; ++axis)
      for (double d : {0.1, 0.3, 0.45}) {
        SCOPED_TRACE("n " + std::to_string(n) + " axis " + std::to_string(axis) + " d " + std::to_string(d));
        const Frame frame = frame_of({make_box(Vec3::Zero(), Vec3::Ones(), n, "a"),
                                      make_box(axis_vector(axis, 1 - d), Vec3::Ones(), n, "b")});
        const auto pd = run_pd(frame);
        ASSERT_EQ(pd.size(), 1u);
        EXPECT_EQ(pd[0].status, PdStatus::Ok) << pd_status_name(pd[0].status);
        EXPECT_LE(std::abs(pd[0].depth - d), 1e-9 * d) << "depth " << pd[0].depth;
        EXPECT_LE((pd[0].direction - axis_vector(axis, -1)).norm(), 1e-12);
        // Every vertex strictly inside the other box is listed, and only those or vertices
        // on its boundary.
        for (int side = 0; side < 2; ++side) {
          const Object& own = frame.objects[static_cast<size_t>(side)];
          const Object& other = frame.objects[static_cast<size_t>(1 - side)];
          Vec3 olo = Vec3::Constant(kInfinity), ohi = Vec3::Constant(-kInfinity);
          for (const Vec3& p : other.positions) {
            olo = olo.cwiseMin(p);
            ohi = ohi.cwiseMax(p);
          }
          const auto& list = pd[0].inside_vertices[static_cast<size_t>(side)];
          for (Index v = 0; v < own.num_vertices(); ++v) {
            const Vec3& p = own.positions[static_cast<size_t>(v)];
            const bool strictly = (p.array() > olo.array()).all() && (p.array() < ohi.array()).all();
            const bool closed = (p.array() >= olo.array()).all() && (p.array() <= ohi.array()).all();
            const bool listed = std::binary_search(list.begin(), list.end(), v);
            if (strictly) {
              EXPECT_TRUE(listed) << "side " << side << " vertex " << v;
            }
            if (listed) {
              EXPECT_TRUE(closed) << "side " << side << " vertex " << v;
            }
          }
        }
      }
  }
}

TEST(PenetrationDepth, VerticesOnTheOtherSurfaceAreOutsideOnEveryFace) {
  // A unit box B inside the box A = [0, 2]^3, lying on one face of A from inside. B's four
  // vertices on that face are on A's surface, so not inside; the other four are. The six
  // placements are the same configuration rotated and mirrored, so they must agree: before,
  // a vertex on a face parallel to the inside test's +x ray counted as inside for the faces
  // y = 0 and z = 0, which made B's inside vertices a set without outside neighbour
  // (too_deep).
  double depth0 = -1;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      SCOPED_TRACE("axis " + std::to_string(axis) + " side " + std::to_string(side));
      Vec3 lo = Vec3::Constant(0.5);
      lo[axis] = side == 0 ? 0.0 : 1.0;
      const Frame frame = frame_of({make_box(Vec3::Zero(), Vec3::Constant(2), 1, "a"),
                                    make_box(lo, Vec3::Ones(), 1, "b")});
      const auto pd = run_pd(frame);
      ASSERT_EQ(pd.size(), 1u);
      EXPECT_EQ(pd[0].status, PdStatus::Ok) << pd_status_name(pd[0].status);
      EXPECT_TRUE(pd[0].inside_vertices[0].empty());
      std::vector<Index> strictly;
      const Object& b = frame.objects[1];
      for (Index v = 0; v < b.num_vertices(); ++v) {
        const Vec3& p = b.positions[static_cast<size_t>(v)];
        if ((p.array() > 0).all() && (p.array() < 2).all()) strictly.push_back(v);
      }
      EXPECT_EQ(strictly.size(), 4u);
      EXPECT_EQ(pd[0].inside_vertices[1], strictly);
      if (depth0 < 0) depth0 = pd[0].depth;
      EXPECT_NEAR(pd[0].depth, depth0, 1e-12);
    }
}

TEST(PenetrationDepth, OffsetBoxesUseTheDeepestVertex) {
  // 12-triangle boxes offset sideways too: corner (1,1,1) of A is inside B, d from B's
  // face x = 1-d and farther from its other faces when d < 0.4.
  for (int axis = 0; axis < 3; ++axis)
    for (double d : {0.05, 0.2, 0.35}) {
      SCOPED_TRACE("axis " + std::to_string(axis) + " d " + std::to_string(d));
      Vec3 offset = axis_vector(axis, 1 - d) + axis_vector((axis + 1) % 3, 0.5) + axis_vector((axis + 2) % 3, 0.4);
      const Frame frame = frame_of({make_box(Vec3::Zero(), Vec3::Ones(), 1, "a"),
                                    make_box(offset, Vec3::Ones(), 1, "b")});
      const auto pd = run_pd(frame);
      ASSERT_EQ(pd.size(), 1u);
      ASSERT_EQ(pd[0].status, PdStatus::Ok) << pd_status_name(pd[0].status);
      EXPECT_LE(std::abs(pd[0].depth - d), 1e-9 * d) << "depth " << pd[0].depth;
      EXPECT_LE((pd[0].direction - axis_vector(axis, -1)).norm(), 1e-12);
      EXPECT_EQ(pd[0].inside_vertices[0].size(), 1u);  // corner (1,1,1) of A
      EXPECT_EQ(pd[0].inside_vertices[1].size(), 1u);  // the opposite corner of B
      EXPECT_NE(pd[0].deepest_vertex, kNoIndex);
    }
}

/// Width along unit u of the lens B(c1, r1) ∩ B(c2, r2): support function in u and -u. The
/// extreme point in direction u is the ball point c + r u of one ball if it lies in the other
/// ball, else a point of the rim circle (where the spheres meet).
double lens_width(const Vec3& c1, double r1, const Vec3& c2, double r2, const Vec3& u) {
  const Vec3 axis = (c2 - c1).normalized();
  const double dist = (c2 - c1).norm();
  const double x = (dist * dist + r1 * r1 - r2 * r2) / (2 * dist);  // rim plane from c1
  const Vec3 m = c1 + x * axis;
  const double a = std::sqrt(r1 * r1 - x * x);  // rim radius
  auto support = [&](const Vec3& w) {
    const Vec3 p1 = c1 + r1 * w, p2 = c2 + r2 * w;
    double h = -kInfinity;
    if ((p1 - c2).norm() <= r2) h = std::max(h, p1.dot(w));
    if ((p2 - c1).norm() <= r1) h = std::max(h, p2.dot(w));
    const Vec3 lateral = w - w.dot(axis) * axis;
    h = std::max(h, m.dot(w) + a * lateral.norm());
    return h;
  };
  return support(u) + support(-u);
}

/// Smallest distance from c to the mesh surface: the mesh lies between the spheres of this
/// radius and of r (every vertex is on the sphere of radius r; the mesh is convex).
double inner_radius(const Object& o, const Vec3& c) {
  double best = kInfinity;
  for (Index t = 0; t < o.num_triangles(); ++t)
    best = std::min(best, std::sqrt(point_triangle_distance(c, o.triangle(t)).squared_distance));
  return best;
}

TEST(PenetrationDepth, IcospheresWithinSamplingError) {
  // Each icosphere (1280 triangles) is a convex polyhedron P_k with B(c_k, ri_k) ⊂ P_k ⊂
  // B(c_k, r_k). The computed depth is the width of P_1 ∩ P_2 along T, so it lies between the
  // width of the inner lens along T (>= its thickness ri1 + ri2 - D: the axis is the lens's
  // narrowest direction) and the width of the outer lens along T. Hence the stated sampling
  // error: |depth - (r1 + r2 - D)| <= max((r1 - ri1) + (r2 - ri2), W_outer(T) - (r1 + r2 - D)).
  struct Case {
    Vec3 c2;
    double r2;
  };
  const double r1 = 1.0;
  const Vec3 c1(0.1, -0.2, 0.3);
  for (const Case& k : {Case{Vec3(1.6, 0.3, 0.1), 0.9}, Case{Vec3(-0.4, 1.2, 1.3), 1.1},
                        Case{Vec3(0.3, -1.5, 0.9), 0.8}}) {
    const Frame frame = frame_of({make_icosphere(c1, r1, 3, "s1"), make_icosphere(k.c2, k.r2, 3, "s2")});
    ASSERT_EQ(frame.objects[0].num_triangles(), 1280);
    const double dist = (k.c2 - c1).norm();
    const double exact = r1 + k.r2 - dist;
    const double ri1 = inner_radius(frame.objects[0], c1), ri2 = inner_radius(frame.objects[1], k.c2);
    const auto pd = run_pd(frame);
    ASSERT_EQ(pd.size(), 1u);
    ASSERT_EQ(pd[0].status, PdStatus::Ok) << pd_status_name(pd[0].status);
    const Vec3 axis = (k.c2 - c1).normalized();
    const double outer = lens_width(c1, r1, k.c2, k.r2, pd[0].direction);
    const double bound = std::max((r1 - ri1) + (k.r2 - ri2), outer - exact);
    const double angle = std::acos(std::min(1.0, -pd[0].direction.dot(axis)));
    std::printf("[ icospheres ] exact %.6f depth %.6f error %.2e bound %.2e (ri: %.5f %.5f) "
                "angle(T, -axis) %.4f rad, inside %zu + %zu vertices\n",
                exact, pd[0].depth, pd[0].depth - exact, bound, ri1, ri2, angle,
                pd[0].inside_vertices[0].size(), pd[0].inside_vertices[1].size());
    EXPECT_GE(pd[0].depth, ri1 + ri2 - dist - 1e-12);
    EXPECT_LE(pd[0].depth, outer + 1e-12);
    EXPECT_LE(std::abs(pd[0].depth - exact), bound);
    EXPECT_LT(angle, 0.5);  // T points from sphere 2 towards sphere 1 (A moves away from B)
    // Inside vertices agree with the balls wherever the balls decide.
    for (int side = 0; side < 2; ++side) {
      const Object& own = frame.objects[static_cast<size_t>(side)];
      const Vec3 oc = side == 0 ? k.c2 : c1;
      const double orad = side == 0 ? k.r2 : r1, oin = side == 0 ? ri2 : ri1;
      const auto& list = pd[0].inside_vertices[static_cast<size_t>(side)];
      for (Index v = 0; v < own.num_vertices(); ++v) {
        const double dv = (own.positions[static_cast<size_t>(v)] - oc).norm();
        const bool listed = std::binary_search(list.begin(), list.end(), v);
        if (dv < oin) {
          EXPECT_TRUE(listed) << "vertex " << v << " deep inside";
        }
        if (dv > orad) {
          EXPECT_FALSE(listed) << "vertex " << v << " outside the ball";
        }
      }
    }
  }
}

// The deepest vertex against the exact brute force: the search's early stop (a vertex nearer
// than the deepest so far) and its pruning by boxes change nothing.
TEST(PenetrationDepth, DeepestVertexIsTheBruteForceMaxMin) {
  for (const Vec3& c2 : {Vec3(0.9, 0.1, 0.0), Vec3(0.4, 0.3, -0.2), Vec3(1.2, 0.5, 0.3)}) {
    const Frame frame = frame_of({make_icosphere(Vec3(0, 0, 0), 1.0, 3, "s1"), make_icosphere(c2, 0.8, 3, "s2")});
    const auto pd = run_pd(frame);
    ASSERT_EQ(pd.size(), 1u);
    ASSERT_EQ(pd[0].status, PdStatus::Ok) << pd_status_name(pd[0].status);
    const test::ExactDeepest expected = test::exact_deepest(frame, pd[0]);
    ASSERT_NE(expected.vertex, kNoIndex);
    EXPECT_EQ(pd[0].deepest_object, expected.object);
    EXPECT_EQ(pd[0].deepest_vertex, expected.vertex);
    EXPECT_EQ(pd[0].nearest_point, expected.nearest);
  }
}

// Boxes on a dyadic grid (every coordinate exact in binary): inside vertices are often
// exactly equally deep, and equally near several faces. Double precision rounds such ties
// either way (a vertex 0.25 from a face computed 0.24999999999999997 from it lost to another
// vertex 0.25 from a face computed exactly): the deepest vertex, its nearest point and so T
// must follow the tie rules of docs/algorithms.md, decided exactly (an independent exact-rational oracle
// found 19 entries out of about 2,450 that did not).
TEST(PenetrationDepth, ExactTiesFollowTheTieRules) {
  test::Rng rng(2024);
  int tied = 0, entries = 0;
  for (int trial = 0; trial < 600; ++trial) {
    std::vector<Object> boxes;
    for (int k = 0; k < 2; ++k) {
      Vec3 lo, size;
      std::array<int, 3> counts{};
      for (int a = 0; a < 3; ++a) {
        lo[a] = rng.integer(0, 8) / 4.0;
        size[a] = rng.integer(2, 8) / 4.0;
        counts[static_cast<size_t>(a)] = 1 << rng.integer(0, 2);
      }
      boxes.push_back(make_grid_box(lo, size, counts).object);
    }
    const Frame frame = frame_of(boxes);
    for (const PenetrationDepth& pd : run_pd(frame)) {
      if (pd.status != PdStatus::Ok || pd.deepest_vertex == kNoIndex) continue;
      ++entries;
      const test::ExactDeepest expected = test::exact_deepest(frame, pd);
      EXPECT_EQ(pd.deepest_object, expected.object) << "trial " << trial;
      EXPECT_EQ(pd.deepest_vertex, expected.vertex) << "trial " << trial;
      EXPECT_EQ(pd.nearest_point, expected.nearest) << "trial " << trial;
      tied += expected.tied > 1;
    }
  }
  std::printf("[ ties ] %d pd entries, %d with exactly equally deep vertices\n", entries, tied);
  EXPECT_GT(entries, 150);
  EXPECT_GT(tied, 50);  // the construction does make ties
}

/// An object from corner positions and 0-based faces.
Object literal_object(std::vector<Vec3> positions, std::vector<Face> faces, const std::string& name) {
  Object o;
  auto topo = std::make_shared<Topology>();
  topo->num_vertices = static_cast<Index>(positions.size());
  topo->faces = std::move(faces);
  o.topology = topo;
  o.positions = std::move(positions);
  o.name = name;
  return o;
}

/// Faces of a 12-triangle box whose corners are numbered (x, y, z) -> 4 (1 - x) + 2 y + z.
const std::vector<Face> kBoxFaces = {{0, 2, 3}, {0, 3, 1}, {4, 7, 6}, {4, 5, 7}, {6, 7, 3}, {6, 3, 2},
                                     {4, 1, 5}, {4, 0, 1}, {5, 1, 3}, {5, 3, 7}, {4, 2, 0}, {4, 6, 2}};
Object literal_box(const Vec3& lo, const Vec3& hi, const std::string& name) {
  std::vector<Vec3> corners;
  for (int x : {1, 0})
    for (int y : {0, 1})
      for (int z : {0, 1}) corners.emplace_back(x ? hi.x() : lo.x(), y ? hi.y() : lo.y(), z ? hi.z() : lo.z());
  return literal_object(corners, kBoxFaces, name);
}

// The two cases the exact oracle reported, worked out by hand from the rules of docs/algorithms.md.
TEST(PenetrationDepth, ExactTiesOfTheOracle) {
  {  // one inside vertex, b's corner 3 = (1.75, 1.25, 1.5), exactly 0.5 from a's faces 1
     // (x = 2.25), 7 (y = 0.75), 8 (z = 2) and 10 (z = 1): the nearest point is on face 1,
     // b moves by -T = +x, the overlap is 1.75 - 0.5 wide along x.
    const Frame frame = frame_of({literal_box(Vec3(0.5, 0.75, 1), Vec3(2.25, 2.5, 2), "a"),
                                  literal_box(Vec3(0.5, 0.75, 0.75), Vec3(1.75, 1.25, 1.5), "b")});
    const auto pd = run_pd(frame);
    ASSERT_EQ(pd.size(), 1u);
    ASSERT_EQ(pd[0].status, PdStatus::Ok);
    EXPECT_EQ(pd[0].deepest_object, 1);
    EXPECT_EQ(pd[0].deepest_vertex, 3);
    EXPECT_EQ(pd[0].nearest_point, Vec3(2.25, 1.25, 1.5));
    EXPECT_EQ(pd[0].direction, Vec3(-1, 0, 0));
    EXPECT_EQ(pd[0].depth, 1.25);
  }
  {  // b (a 1 x 2 x 1 grid box) has three inside corners, (2.25, y, 2) for y = 0.5, 0.75, 1,
     // each exactly 0.25 from a (the first also from a's face y = 0.25, computed
     // 0.24999999999999997): the smallest id wins, its nearest point is on y = 0.25, and the
     // overlap is 1 - 0.5 wide along y.
    const std::vector<Vec3> b_corners = {{2.25, 0.5, 0.25}, {2.25, 0.5, 2.0}, {2.25, 0.75, 0.25}, {2.25, 0.75, 2.0},
                                         {2.25, 1.0, 0.25}, {2.25, 1.0, 2.0}, {1.0, 0.5, 0.25},   {1.0, 0.5, 2.0},
                                         {1.0, 0.75, 0.25}, {1.0, 0.75, 2.0}, {1.0, 1.0, 0.25},   {1.0, 1.0, 2.0}};
    const std::vector<Face> b_faces = {{0, 2, 3},  {0, 3, 1},  {2, 4, 5},  {2, 5, 3},  {6, 9, 8},  {6, 7, 9},  {8, 11, 10},
                                       {8, 9, 11}, {10, 11, 5}, {10, 5, 4}, {6, 1, 7},  {6, 0, 1},  {7, 1, 3},  {7, 3, 9},
                                       {9, 3, 5},  {9, 5, 11}, {6, 2, 0},  {6, 8, 2},  {8, 4, 2},  {8, 10, 4}};
    const Frame frame = frame_of({literal_box(Vec3(1.25, 0.25, 0.5), Vec3(3, 1.5, 2.25), "a"),
                                  literal_object(b_corners, b_faces, "b")});
    const auto pd = run_pd(frame);
    ASSERT_EQ(pd.size(), 1u);
    ASSERT_EQ(pd[0].status, PdStatus::Ok);
    EXPECT_EQ(pd[0].inside_vertices[1], (std::vector<Index>{1, 3, 5}));
    EXPECT_EQ(pd[0].deepest_object, 1);
    EXPECT_EQ(pd[0].deepest_vertex, 1);
    EXPECT_EQ(pd[0].nearest_point, Vec3(2.25, 0.25, 2));
    EXPECT_EQ(pd[0].direction, Vec3(0, 1, 0));
    EXPECT_EQ(pd[0].depth, 0.5);
  }
}

TEST(PenetrationDepth, ThreadCountDoesNotChangeResults) {
  const Frame frame = frame_of({make_icosphere(Vec3::Zero(), 1.0, 2, "s1"), make_icosphere(Vec3(1.5, 0.2, 0), 0.8, 2, "s2"),
                                make_box(Vec3(0.5, -0.3, -0.2), Vec3(1.2, 0.5, 0.4), 3, "box")});
  const auto a = run_pd(frame, 1), b = run_pd(frame, 3);
  ASSERT_EQ(a.size(), 3u);
  test::expect_same_pd(a, b, "threads 1 vs 3");
}

TEST(PenetrationDepth, UndefinedCasesGetAStatus) {
  const Object a = make_box(Vec3::Zero(), Vec3::Ones(), 2, "a");
  const Object b = make_box(Vec3(0.7, 0.2, 0.1), Vec3::Ones(), 2, "b");
  {  // B with one face removed: open
    Object open = b;
    auto topo = std::make_shared<Topology>(*b.topology);
    topo->faces.pop_back();
    open.topology = topo;
    const auto pd = run_pd(frame_of({a, open}));
    ASSERT_EQ(pd.size(), 1u);
    EXPECT_EQ(pd[0].status, PdStatus::OpenSurface);
  }
  {  // B with one face flipped: inconsistently oriented
    Object flipped = b;
    auto topo = std::make_shared<Topology>(*b.topology);
    std::swap(topo->faces[3][1], topo->faces[3][2]);
    flipped.topology = topo;
    const auto pd = run_pd(frame_of({a, flipped}));
    ASSERT_EQ(pd.size(), 1u);
    EXPECT_EQ(pd[0].status, PdStatus::NonOrientable);
  }
  {  // An edge shared by four faces: two boxes of one object touching along an edge
    Object two = make_box(Vec3(0.7, 0.2, 0.1), Vec3::Ones(), 1, "b");
    const Object c = make_box(Vec3(1.7, 1.2, 0.1), Vec3::Ones(), 1, "c");
    auto topo = std::make_shared<Topology>(*two.topology);
    // Weld c's vertices onto two's where they coincide (the shared edge x=1.7, y=1.2).
    std::vector<Index> map;
    for (const Vec3& p : c.positions) {
      Index id = kNoIndex;
      for (Index v = 0; v < static_cast<Index>(two.positions.size()); ++v)
        if (two.positions[static_cast<size_t>(v)] == p) id = v;
      if (id == kNoIndex) {
        id = static_cast<Index>(two.positions.size());
        two.positions.push_back(p);
      }
      map.push_back(id);
    }
    for (const Face& f : c.topology->faces)
      topo->faces.push_back({map[static_cast<size_t>(f[0])], map[static_cast<size_t>(f[1])], map[static_cast<size_t>(f[2])]});
    topo->num_vertices = static_cast<Index>(two.positions.size());
    two.topology = topo;
    const auto pd = run_pd(frame_of({a, two}));
    ASSERT_GE(pd.size(), 1u);
    EXPECT_EQ(pd[0].status, PdStatus::NonManifold);
  }
  {  // A small box swallowed by B, whose dented top reaches into it: all of A is inside B.
    Object big = make_box(Vec3::Zero(), Vec3::Constant(3), 2, "big");
    for (Vec3& p : big.positions)
      if (p == Vec3(1.5, 1.5, 3)) p = Vec3(1.5, 1.5, 1);  // centre of the top face pushed down
    const Object small = make_box(Vec3(1, 1, 0.5), Vec3::Ones(), 1, "small");
    const auto pd = run_pd(frame_of({big, small}));
    ASSERT_EQ(pd.size(), 1u);
    EXPECT_EQ(pd[0].status, PdStatus::TooDeep) << pd_status_name(pd[0].status);
    EXPECT_EQ(pd[0].inside_vertices[1].size(), 8u);
  }
}

TEST(PenetrationDepth, InsideVerticesAreTheWalkClosureOfBruteForceWinding) {
  // On random overlapping blobs: the listed vertices of each side are exactly those reached
  // from the intersecting triangles' vertices through vertices inside the other object, with
  // "inside" from the brute-force winding number (every face, no BVH).
  size_t checked = 0, ok = 0;
  for (std::uint64_t seed = 1; seed <= 8; ++seed) {
    const Frame frame = test::make_random_frame(seed, 4, 1.0, 2);
    const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
    const auto pairs = intersecting_pairs(frame, boxes, {2, nullptr, false}).pairs;
    const auto pd = penetration_depth(frame, boxes, pairs, {2}).pairs;
    for (const PenetrationDepth& e : pd) {
      SCOPED_TRACE("seed " + std::to_string(seed) + " objects " + std::to_string(e.objects[0]) + "," + std::to_string(e.objects[1]));
      if (e.status != PdStatus::Ok && e.status != PdStatus::TooDeep) continue;
      if (e.status == PdStatus::Ok) {
        ++ok;
        EXPECT_GE(e.depth, 0.0);
        EXPECT_NEAR(e.direction.norm(), 1.0, 1e-12);
      }
      checked += test::expect_inside_is_walk_closure(frame, e, pairs);
    }
  }
  std::printf("[ blobs ] %zu pd entries ok, %zu inside vertices checked\n", ok, checked);
  EXPECT_GT(checked, 50u);
  EXPECT_GT(ok, 3u);
}

// ---------------------------------------------------------------------------------------
// Self-intersections: one closed, consistently oriented object whose sheets overlap.
// ---------------------------------------------------------------------------------------


/// The objects as one object (vertex ids of objects[k] shifted by the earlier vertex counts).
Object merge(const std::vector<Object>& parts, const std::string& name) {
  Object m;
  auto topo = std::make_shared<Topology>();
  for (const Object& p : parts) {
    const Index base = static_cast<Index>(m.positions.size());
    m.positions.insert(m.positions.end(), p.positions.begin(), p.positions.end());
    for (const Face& f : p.topology->faces) topo->faces.push_back({f[0] + base, f[1] + base, f[2] + base});
  }
  topo->num_vertices = static_cast<Index>(m.positions.size());
  m.topology = topo;
  m.name = name;
  return m;
}

Object flip_all(const Object& o) {
  Object f = o;
  auto topo = std::make_shared<Topology>(*o.topology);
  for (Face& face : topo->faces) std::swap(face[1], face[2]);
  f.topology = topo;
  return f;
}

/// Every directed edge used once and its reverse once: closed and consistently oriented.
bool closed_and_oriented(const Object& o) {
  std::map<std::pair<Index, Index>, int> used;
  for (const Face& f : o.topology->faces)
    for (int k = 0; k < 3; ++k) ++used[{f[static_cast<size_t>(k)], f[static_cast<size_t>((k + 1) % 3)]}];
  for (const auto& [e, n] : used) {
    if (n != 1) return false;
    const auto r = used.find({e.second, e.first});
    if (r == used.end() || r->second != 1) return false;
  }
  return true;
}

/// Box A = [0,1]^3 and box B = [1-d, 2-d] x [0.25, 0.85] x [0.15, 0.95] (cells of 0.1, no
/// grid line of one on a face plane of the other): they overlap in the slab [1-d, 1] along
/// x, whose thinnest extent is d (d < 0.3). `bridged` joins them into ONE closed surface: a
/// square tube (a U with mitred corners) from a bottom cell of A (x in [0.2, 0.3]) down to
/// z = -0.6, across below both boxes and up into a bottom cell of B (x in [1.6-d, 1.7-d],
/// beyond A), touching nothing else.
struct BoxPair {
  Object a, b;   // the plain boxes
  Object bridged;
  double depth;  // exact: A's max x minus B's min x, as stored
};
BoxPair make_box_pair(double d) {
  BoxPair out;
  const Vec3 blo(1 - d, 0.25, 0.15), bsize(1, 0.6, 0.8);
  out.a = make_grid_box(Vec3::Zero(), Vec3::Ones(), {10, 10, 10}).object;
  out.b = make_grid_box(blo, bsize, {10, 6, 8}).object;
  const HoledBox ha = make_grid_box(Vec3::Zero(), Vec3::Ones(), {10, 10, 10}, {2, 0, 2, 4});
  const HoledBox hb = make_grid_box(blo, bsize, {10, 6, 8}, {2, 0, 6, 2});
  Object m = merge({ha.object, hb.object}, "bridged");
  auto topo = std::make_shared<Topology>(*m.topology);
  const Index base_b = ha.object.num_vertices();
  // Rings of the tube, corner k of each matching corner k of A's hole (offset (dx, dy) from
  // the hole's centre): A's hole; the mitred ring of the turn from -z to +x at K1 (corner
  // K1 + dx (x + z) + dy y); that of the turn from +x to +z at K2 (K2 + dx (z - x) + dy y);
  // B's hole, where the U-turn has mirrored the offsets: corner k is B's corner at (-dx, dy).
  std::array<std::array<Index, 4>, 4> rings;
  rings[0] = ha.hole_ring;
  const std::array<Index, 4> mirrored{hb.hole_ring[1], hb.hole_ring[0], hb.hole_ring[3], hb.hole_ring[2]};
  for (int k = 0; k < 4; ++k) rings[3][static_cast<size_t>(k)] = mirrored[static_cast<size_t>(k)] + base_b;
  const Vec3 centre_a(0.25, 0.45, 0), k1(0.25, 0.45, -0.6), k2(1.65 - d, 0.5, -0.6);
  for (int r : {1, 2})
    for (int k = 0; k < 4; ++k) {
      const Vec3 off = m.positions[static_cast<size_t>(rings[0][static_cast<size_t>(k)])] - centre_a;
      const Vec3 p = r == 1 ? Vec3(k1 + Vec3(off.x(), off.y(), off.x())) : Vec3(k2 + Vec3(-off.x(), off.y(), off.x()));
      rings[static_cast<size_t>(r)][static_cast<size_t>(k)] = static_cast<Index>(m.positions.size());
      m.positions.push_back(p);
    }
  std::vector<Face> tube;
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 4; ++k) {
      const Index a = rings[static_cast<size_t>(r)][static_cast<size_t>(k)];
      const Index b = rings[static_cast<size_t>(r)][static_cast<size_t>((k + 1) % 4)];
      const Index c = rings[static_cast<size_t>(r + 1)][static_cast<size_t>((k + 1) % 4)];
      const Index e = rings[static_cast<size_t>(r + 1)][static_cast<size_t>(k)];
      tube.push_back({a, b, c});
      tube.push_back({a, c, e});
    }
  topo->num_vertices = static_cast<Index>(m.positions.size());
  const size_t boxes_faces = topo->faces.size();
  topo->faces.insert(topo->faces.end(), tube.begin(), tube.end());
  m.topology = topo;
  if (!closed_and_oriented(m)) {  // the tube's winding was the other way round
    for (size_t f = boxes_faces; f < topo->faces.size(); ++f) std::swap(topo->faces[f][1], topo->faces[f][2]);
  }
  out.bridged = m;
  double amax = -kInfinity, bmin = kInfinity;
  for (const Vec3& p : out.a.positions) amax = std::max(amax, p.x());
  for (const Vec3& p : out.b.positions) bmin = std::min(bmin, p.x());
  out.depth = amax - bmin;
  return out;
}

TEST(PenetrationDepthSelf, BridgedBoxesGiveDepthDAndMatchTheTwin) {
  for (double d : {0.05, 0.15, 0.25}) {
    SCOPED_TRACE("d " + std::to_string(d));
    const BoxPair bp = make_box_pair(d);
    ASSERT_TRUE(closed_and_oriented(bp.bridged));
    const Index na = bp.a.num_vertices();
    // The one object: its sheets intersect (intra pairs only) and are connected by the tube.
    const Frame self_frame = frame_of({bp.bridged});
    const FrameBoxes boxes = FrameBoxes::compute(self_frame, 2);
    const auto pairs = intersecting_pairs(self_frame, boxes, {2, nullptr, true}).pairs;
    ASSERT_FALSE(pairs.empty());
    for (const IntersectingPair& p : pairs) {  // only box-against-box pairs: the tube is clear
      const Face& fa = bp.bridged.topology->faces[static_cast<size_t>(p.tri_a)];
      const Face& fb = bp.bridged.topology->faces[static_cast<size_t>(p.tri_b)];
      EXPECT_TRUE((fa[0] < na) != (fb[0] < na)) << p.tri_a << " " << p.tri_b;
    }
    const auto self = penetration_depth(self_frame, boxes, pairs, {2}).pairs;
    ASSERT_EQ(self.size(), 1u);
    EXPECT_EQ(self[0].objects, (std::array<Index, 2>{0, 0}));
    ASSERT_EQ(self[0].status, PdStatus::Ok) << pd_status_name(self[0].status);
    EXPECT_LE(std::abs(self[0].depth - bp.depth), 1e-9 * bp.depth) << "depth " << self[0].depth;
    EXPECT_LE(std::abs(std::abs(self[0].direction.x()) - 1), 1e-12) << self[0].direction.transpose();
    EXPECT_NE(self[0].deepest_vertex, kNoIndex);
    // The twin: the same boxes as two objects, through the inter-object path.
    const auto twin = run_pd(frame_of({bp.a, bp.b}));
    ASSERT_EQ(twin.size(), 1u);
    ASSERT_EQ(twin[0].status, PdStatus::Ok);
    EXPECT_LE(std::abs(twin[0].depth - bp.depth), 1e-9 * bp.depth);
    EXPECT_LE(std::abs(self[0].depth - twin[0].depth), 1e-9 * bp.depth);
    EXPECT_LE(std::abs(std::abs(self[0].direction.dot(twin[0].direction)) - 1), 1e-12);
    // Same overlapping features: the vertices of A inside B and of B inside A (B's ids are
    // shifted by A's vertex count in the merged object; the holes removed faces only).
    std::vector<Index> twin_inside = twin[0].inside_vertices[0];
    for (Index v : twin[0].inside_vertices[1]) twin_inside.push_back(v + na);
    std::vector<Index> self_inside = self[0].inside_vertices[0];
    self_inside.insert(self_inside.end(), self[0].inside_vertices[1].begin(), self[0].inside_vertices[1].end());
    std::sort(twin_inside.begin(), twin_inside.end());
    std::sort(self_inside.begin(), self_inside.end());
    EXPECT_EQ(self_inside, twin_inside);
    EXPECT_GT(self_inside.size(), 10u);
    std::printf("[ self bridged ] d %.2f exact %.17g self %.17g twin %.17g, %zu pairs, %zu inside vertices\n", d,
                bp.depth, self[0].depth, twin[0].depth, pairs.size(), self_inside.size());

    // The same surface with every face flipped (inward-oriented), and the two boxes as one
    // object of two components without the tube: the same depth.
    for (const Object& variant : {flip_all(bp.bridged), merge({bp.a, bp.b}, "merged"), flip_all(merge({bp.a, bp.b}, "m"))}) {
      const auto pd = run_pd(frame_of({variant}));
      ASSERT_EQ(pd.size(), 1u);
      ASSERT_EQ(pd[0].status, PdStatus::Ok) << pd_status_name(pd[0].status);
      EXPECT_LE(std::abs(pd[0].depth - bp.depth), 1e-9 * bp.depth) << "depth " << pd[0].depth;
      EXPECT_LE(std::abs(std::abs(pd[0].direction.x()) - 1), 1e-12);
    }
  }
}

TEST(PenetrationDepthSelf, DentPushedThroughTheBottomIsAnInwardFold) {
  // The box [0,3]^3 with the centre of its top face pushed down to (1.5, 1.5, -d): the dent
  // goes through the bottom face, enclosing a region of winding number -1 below it, d thick.
  // Its tip is the deepest vertex, nearest to the bottom face straight above it: T = +z
  // (the dent's sheet moves up), depth d. The same with the faces flipped.
  for (double d : {0.2, 0.7}) {
    Object dented = make_box(Vec3::Zero(), Vec3::Constant(3), 2, "dented");
    Index tip = kNoIndex;
    for (Index v = 0; v < dented.num_vertices(); ++v)
      if (dented.positions[static_cast<size_t>(v)] == Vec3(1.5, 1.5, 3)) {
        dented.positions[static_cast<size_t>(v)] = Vec3(1.5, 1.5, -d);
        tip = v;
      }
    ASSERT_NE(tip, kNoIndex);
    for (const Object& o : {dented, flip_all(dented)}) {
      SCOPED_TRACE("d " + std::to_string(d));
      const auto pd = run_pd(frame_of({o}));
      ASSERT_EQ(pd.size(), 1u);
      ASSERT_EQ(pd[0].status, PdStatus::Ok) << pd_status_name(pd[0].status);
      EXPECT_LE(std::abs(pd[0].depth - d), 1e-9 * d) << "depth " << pd[0].depth;
      EXPECT_LE((pd[0].direction - Vec3(0, 0, 1)).norm(), 1e-12) << pd[0].direction.transpose();
      EXPECT_EQ(pd[0].deepest_vertex, tip);
      EXPECT_EQ(pd[0].reason, PdReason::None);
      EXPECT_EQ(pd[0].reason_features, (std::array<Index, 2>{kNoIndex, kNoIndex}));
      EXPECT_EQ(pd[0].inside_vertices[0], std::vector<Index>{tip});
      ASSERT_EQ(pd[0].inside_vertices[1].size(), 1u);  // the bottom's centre, in the dent
      EXPECT_EQ(o.positions[static_cast<size_t>(pd[0].inside_vertices[1][0])], Vec3(1.5, 1.5, 0));
    }
  }
}

TEST(PenetrationDepthSelf, StarFoldedFlatAtASeedIsUndecided) {
  // The dented box above (d = 0.7), with the bottom's centre, a vertex of the triangles the dent
  // goes through, moved within the bottom plane to (1.5, -0.375, 0), past its ring's edge at
  // y = 0: the star's triangles on that edge turn over and cover their neighbours in the plane
  // z = 0 (a flat fold). Which sheet is which cannot be told there: self_intersection. The
  // covering faces are parallel to the +x ray, which only found covers by faces it crosses.
  Object dented = make_box(Vec3::Zero(), Vec3::Constant(3), 2, "dented");
  for (Vec3& p : dented.positions) {
    if (p == Vec3(1.5, 1.5, 3)) p = Vec3(1.5, 1.5, -0.7);
    else if (p == Vec3(1.5, 1.5, 0)) p = Vec3(1.5, -0.375, 0);
  }
  Index moved = kNoIndex;
  for (Index v = 0; v < dented.num_vertices(); ++v)
    if (dented.positions[static_cast<size_t>(v)] == Vec3(1.5, -0.375, 0)) moved = v;
  ASSERT_NE(moved, kNoIndex);
  const Adjacency& adj = adjacency(*dented.topology);
  for (const Object& o : {dented, flip_all(dented)}) {
    const auto pd = run_pd(frame_of({o}));
    ASSERT_EQ(pd.size(), 1u);
    EXPECT_EQ(pd[0].status, PdStatus::SelfIntersection) << pd_status_name(pd[0].status);
    // The reason: a flat fold, at the moved vertex or a vertex of its ring (the turned-over
    // triangles are in their stars too), whose star has two faces in one plane.
    EXPECT_EQ(pd[0].reason, PdReason::FlatFold) << pd_reason_name(pd[0].reason);
    const Index at = pd[0].reason_features[0];
    EXPECT_EQ(pd[0].reason_features[1], kNoIndex);
    bool near_moved = at == moved;
    for (Index t : adj.vertex_triangles(moved))
      for (Index u : o.topology->faces[static_cast<size_t>(t)]) near_moved = near_moved || u == at;
    EXPECT_TRUE(near_moved) << at;
    bool coplanar_pair = false;
    for (Index f : adj.vertex_triangles(at))
      for (Index g : adj.vertex_triangles(at)) {
        const Triangle tf = o.triangle(f);
        if (f == g) continue;
        bool all = true;
        for (const Vec3& x : o.triangle(g)) all = all && orient3d(tf[0], tf[1], tf[2], x) == 0;
        coplanar_pair = coplanar_pair || all;
      }
    EXPECT_TRUE(coplanar_pair);
  }
}

/// A box [0,3]^3 of 2 cells per axis with a degenerate "pillow" attached at the centre of its
/// -x face a: faces (v, a, b) and (v, b, a) with v the midpoint of a and b, a closed,
/// oriented two-face surface of zero area (vertex a is then shared by two fans; every edge
/// is still used once in each direction). The segment a-b crosses the box's surface, so the
/// pillow's faces intersect a face of the box that does not contain a.
struct Pillowed {
  Object object;
  Index v = kNoIndex, b = kNoIndex;
};
Pillowed pillowed_box(const Vec3& b_position) {
  Object box = make_box(Vec3::Zero(), Vec3::Constant(3), 2, "pillowed");
  Index a = kNoIndex;
  for (Index k = 0; k < box.num_vertices(); ++k)
    if (box.positions[static_cast<size_t>(k)] == Vec3(0, 1.5, 1.5)) a = k;
  EXPECT_NE(a, kNoIndex);
  std::vector<Vec3> positions = box.positions;
  std::vector<Face> faces = box.topology->faces;
  Pillowed out;
  out.v = static_cast<Index>(positions.size());
  positions.push_back(0.5 * (positions[static_cast<size_t>(a)] + b_position));  // exact: dyadic
  out.b = static_cast<Index>(positions.size());
  positions.push_back(b_position);
  faces.push_back({out.v, a, out.b});
  faces.push_back({out.v, out.b, a});
  out.object = literal_object(positions, faces, "pillowed");
  return out;
}

TEST(PenetrationDepthSelf, UndecidedPillowGivesItsReason) {
  // Where the pillow leaves through the +y face (b at x = 2), the box's corner (3, 3, 3) stays
  // the lexicographically largest vertex, whose w_out is decided; v and b have only the
  // pillow's faces, which have no normal: reason degenerate_star, at the smaller of them.
  // Where it leaves through the +x face (b at x = 4), b is the component's largest vertex,
  // where its w_out is read, and its star is degenerate: reason reference_vertex, at b.
  for (const bool through_x : {false, true}) {
    SCOPED_TRACE(through_x ? "through +x" : "through +y");
    const Pillowed p = pillowed_box(through_x ? Vec3(4, 1.25, 1.375) : Vec3(2, 4, 1.375));
    ASSERT_TRUE(closed_and_oriented(p.object));
    const auto pd = run_pd(frame_of({p.object}));
    ASSERT_EQ(pd.size(), 1u);
    ASSERT_EQ(pd[0].status, PdStatus::SelfIntersection) << pd_status_name(pd[0].status);
    EXPECT_EQ(pd[0].reason, through_x ? PdReason::ReferenceVertex : PdReason::DegenerateStar)
        << pd_reason_name(pd[0].reason);
    EXPECT_EQ(pd[0].reason_features, (std::array<Index, 2>{through_x ? p.b : std::min(p.v, p.b), kNoIndex}));
  }
}

/// PD of boxes a and b as two objects (the twin) and as one object of two components (self),
/// both asserted to be one entry with status Ok.
std::pair<PenetrationDepth, PenetrationDepth> twin_and_self(const Object& a, const Object& b) {
  const auto twin = run_pd(frame_of({a, b}));
  const auto self = run_pd(frame_of({merge({a, b}, "ab")}));
  EXPECT_EQ(twin.size(), 1u);
  EXPECT_EQ(self.size(), 1u);
  if (twin.size() != 1 || self.size() != 1) return {};
  EXPECT_EQ(twin[0].status, PdStatus::Ok);
  EXPECT_EQ(self[0].status, PdStatus::Ok) << pd_status_name(self[0].status);
  return {twin[0], self[0]};
}

TEST(PenetrationDepthSelf, CoarseMergedBoxesMatchTheTwin) {
  // 12-triangle boxes offset along all axes, as one object of two components: every
  // triangle near the contact intersects, each side has a single inside corner. The self
  // path must reproduce the inter-object answer (no simple closed form here: the deepest
  // corner is nearest to a side face, so this is the paper's local estimate).
  for (const Vec3& offset : {Vec3(0.5, 0.2, 0.3), Vec3(-0.3, 0.6, -0.45), Vec3(0.7, -0.1, 0.25)}) {
    const Object a = make_box(Vec3::Zero(), Vec3::Ones(), 1, "a");
    const Object b = make_box(offset, Vec3::Ones(), 1, "b");
    const auto [twin, self] = twin_and_self(a, b);
    EXPECT_GT(self.depth, 0.0);
    EXPECT_LE(std::abs(self.depth - twin.depth), 1e-12) << self.depth << " vs " << twin.depth;
    EXPECT_LE(std::abs(std::abs(self.direction.dot(twin.direction)) - 1), 1e-12);
  }
}

TEST(PenetrationDepthSelf, SheetRunningOnAcrossAnEdgeIsNotTheTarget) {
  // Boxes sharing their x and z side planes, overlapping 0.75 in y; a's bottom face (y =
  // 0.375, split in four) lies inside b with only its centre strictly inside. As one object,
  // the triangles of a's sides meet b's sides (coplanar) along the edges of a's bottom face,
  // which lie in b's side faces: the curve runs over those edges onto a's sides, which are
  // a's own sheet. Taking them as the other sheet gave the bottom face's corner, 0.71 away
  // (depth 2.83 along a diagonal), instead of b's bottom, 0.75 below (the twin's answer).
  const Object a = make_box(Vec3(0.25, 0.375, -2.5), Vec3::Constant(2), 2, "a");
  const Object b = make_box(Vec3(0.25, -0.875, -2.5), Vec3::Constant(2), 1, "b");
  const auto [twin, self] = twin_and_self(a, b);
  EXPECT_EQ(twin.depth, 0.75);
  EXPECT_EQ(self.depth, 0.75);
  EXPECT_LE(std::abs(std::abs(self.direction.y()) - 1), 1e-12) << self.direction.transpose();
}

/// An object from integer coordinates (x, y, z of each vertex) divided by `denominator`, and
/// three 0-based corners per face, as an oracle's generator wrote them.
Object scaled_literal(const std::vector<int>& coordinates, double denominator, const std::vector<Index>& corners,
                      const std::string& name) {
  std::vector<Vec3> positions;
  for (size_t k = 0; k < coordinates.size(); k += 3)
    positions.emplace_back(coordinates[k] / denominator, coordinates[k + 1] / denominator, coordinates[k + 2] / denominator);
  std::vector<Face> faces;
  for (size_t k = 0; k < corners.size(); k += 3) faces.push_back({corners[k], corners[k + 1], corners[k + 2]});
  return literal_object(positions, faces, name);
}

TEST(PenetrationDepthSelf, OverlappingTrianglesIntersectOrTouchAnInsideVertex) {
  // An independent oracle's case, as its generator wrote it (the vertex order decides which
  // flood holds the deepest vertex): the unit box (4 x 4 x 2 cells) with its top's interior
  // vertices pushed down to z = -1/4 through the bottom, and the top rim's vertex (0.25, 0, 1)
  // moved onto the box edge x = y = 0 at z = 0.75. Triangle 57, (0, 0, 0.5), (0.25, 0, 0.5),
  // (0, 0, 0.75), then meets face 19 of the other sheet along that edge, where the two share a
  // vertex (no intersecting pair), and was listed as overlapping; docs/algorithms.md step 2 lists only the
  // intersecting triangles and those touching an inside vertex.
  const std::vector<int> quarters = {  // x, y, z of each vertex, times 4
      4, 0, 0, 4, 0, 2, 4, 0, 4, 4, 1, 0, 4, 1, 2, 4, 1, 4, 4, 2, 0, 4, 2, 2, 4, 2, 4, 4, 3, 0,
      4, 3, 2, 4, 3, 4, 4, 4, 0, 4, 4, 2, 4, 4, 4, 0, 0, 0, 0, 0, 2, 0, 0, 4, 0, 1, 0, 0, 1, 2,
      0, 1, 4, 0, 2, 0, 0, 2, 2, 0, 2, 4, 0, 3, 0, 0, 3, 2, 0, 3, 4, 0, 4, 0, 0, 4, 2, 0, 4, 4,
      1, 4, 0, 2, 4, 0, 3, 4, 0, 1, 4, 2, 2, 4, 2, 3, 4, 2, 1, 4, 4, 2, 4, 4, 3, 4, 4, 1, 0, 0,
      2, 0, 0, 3, 0, 0, 1, 0, 2, 2, 0, 2, 3, 0, 2, 0, 0, 3, 2, 0, 4, 3, 0, 4, 1, 1, -1, 1, 2, -1,
      1, 3, -1, 2, 1, -1, 2, 2, -1, 2, 3, -1, 3, 1, -1, 3, 2, -1, 3, 3, -1, 1, 1, 0, 1, 2, 0, 1, 3, 0,
      2, 1, 0, 2, 2, 0, 2, 3, 0, 3, 1, 0, 3, 2, 0, 3, 3, 0,
  };
  const std::vector<Index> corners = {  // three per face, 0-based
      0, 3, 4, 0, 4, 1, 1, 4, 5, 1, 5, 2, 3, 6, 7, 3, 7, 4, 4, 7, 8, 4, 8, 5, 6, 9, 10, 6, 10, 7, 7, 10,
      11, 7, 11, 8, 9, 12, 13, 9, 13, 10, 10, 13, 14, 10, 14, 11, 15, 19, 18, 15, 16, 19, 16, 20, 19, 16, 17, 20, 18, 22, 21, 18,
      19, 22, 19, 23, 22, 19, 20, 23, 21, 25, 24, 21, 22, 25, 22, 26, 25, 22, 23, 26, 24, 28, 27, 24, 25, 28, 25, 29, 28, 25, 26, 29,
      27, 28, 33, 27, 33, 30, 30, 33, 34, 30, 34, 31, 31, 34, 35, 31, 35, 32, 32, 35, 13, 32, 13, 12, 28, 29, 36, 28, 36, 33, 33, 36,
      37, 33, 37, 34, 34, 37, 38, 34, 38, 35, 35, 38, 14, 35, 14, 13, 15, 42, 16, 15, 39, 42, 39, 43, 42, 39, 40, 43, 40, 44, 43, 40,
      41, 44, 41, 1, 44, 41, 0, 1, 16, 45, 17, 16, 42, 45, 42, 46, 45, 42, 43, 46, 43, 47, 46, 43, 44, 47, 44, 2, 47, 44, 1, 2,
      17, 45, 48, 17, 48, 20, 20, 48, 49, 20, 49, 23, 23, 49, 50, 23, 50, 26, 26, 50, 36, 26, 36, 29, 45, 46, 51, 45, 51, 48, 48, 51,
      52, 48, 52, 49, 49, 52, 53, 49, 53, 50, 50, 53, 37, 50, 37, 36, 46, 47, 54, 46, 54, 51, 51, 54, 55, 51, 55, 52, 52, 55, 56, 52,
      56, 53, 53, 56, 38, 53, 38, 37, 47, 2, 5, 47, 5, 54, 54, 5, 8, 54, 8, 55, 55, 8, 11, 55, 11, 56, 56, 11, 14, 56, 14, 38,
      15, 57, 39, 15, 18, 57, 18, 58, 57, 18, 21, 58, 21, 59, 58, 21, 24, 59, 24, 30, 59, 24, 27, 30, 39, 60, 40, 39, 57, 60, 57, 61,
      60, 57, 58, 61, 58, 62, 61, 58, 59, 62, 59, 31, 62, 59, 30, 31, 40, 63, 41, 40, 60, 63, 60, 64, 63, 60, 61, 64, 61, 65, 64, 61,
      62, 65, 62, 32, 65, 62, 31, 32, 41, 3, 0, 41, 63, 3, 63, 6, 3, 63, 64, 6, 64, 9, 6, 64, 65, 9, 65, 12, 9, 65, 32, 12,
  };
  const Object o = scaled_literal(quarters, 4, corners, "dented");
  ASSERT_TRUE(closed_and_oriented(o));
  const Frame frame = frame_of({o});
  const FrameBoxes boxes = FrameBoxes::compute(frame, 2);
  const auto pairs = intersecting_pairs(frame, boxes, {2, nullptr, true}).pairs;
  const auto pd = penetration_depth(frame, boxes, pairs, {2}).pairs;
  ASSERT_EQ(pd.size(), 1u);
  ASSERT_EQ(pd[0].status, PdStatus::Ok) << pd_status_name(pd[0].status);
  EXPECT_EQ(pd[0].depth, 1.0);
  std::vector<Index> inside = pd[0].inside_vertices[0];
  inside.insert(inside.end(), pd[0].inside_vertices[1].begin(), pd[0].inside_vertices[1].end());
  std::sort(inside.begin(), inside.end());
  EXPECT_EQ(inside.size(), 18u);
  for (int side = 0; side < 2; ++side)
    for (Index t : pd[0].overlapping_triangles[static_cast<size_t>(side)]) {
      bool listed = false;
      for (const IntersectingPair& p : pairs) listed = listed || p.tri_a == t || p.tri_b == t;
      for (Index v : o.topology->faces[static_cast<size_t>(t)])
        listed = listed || std::binary_search(inside.begin(), inside.end(), v);
      EXPECT_TRUE(listed) << "triangle " << t;
    }
}

TEST(PenetrationDepthSelf, FoldedStarIsOnTheCurve) {
  // An independent oracle's case (a random fold of a box with dyadic jitter, as its generator
  // wrote it): faces 93 and 96 of vertex 59's star share only that vertex and cross each
  // other, so the star passes through itself at 59, a vertex of the contact. Its w_out was
  // read from its first face: 0 from five of its faces, -1 from face 96, so with face 96
  // moved to the front of the list the entry became self_intersection instead of depth 1.133.
  // w_out is now read from every face of the star; where they differ, the vertex lies on the
  // curve (not inside), whatever the face order.
  const std::vector<int> sixty_fourths = {  // x, y, z of each vertex, times 64
      63, 0, 1, 64, 1, 17, 66, 0, 30, 64, 0, 48, 63, 2, 65, 62, 17, 2, 62, 18, 14, 62, 15, 32, 65,
      15, 47, 62, 15, 62, 64, 33, -1, 66, 34, 18, 64, 30, 30, 62, 34, 49, 64, 32, 66, 66, 47, -2,
      63, 50, 17, 62, 46, 33, 64, 48, 46, 63, 46, 63, 63, 63, 0, 65, 63, 17, 64, 66, 32, 62, 63, 48,
      62, 63, 66, 1, -1, -2, -1, -2, 16, -1, 2, 31, 1, -1, 47, 2, 0, 66, -1, 18, 0, 0, 18, 18, 2,
      14, 33, -2, 15, 47, -2, 17, 63, 0, 34, 2, 0, 34, 16, -2, 31, 30, -1, 31, 48, 0, 33, 62, 1, 47,
      2, 2, 50, 15, 2, 46, 32, -1, 50, 46, -2, 48, 65, 1, 66, 1, -2, 65, 14, -1, 63, 34, -1, 62, 48,
      1, 64, 65, 32, 65, 1, 31, 62, 17, 33, 62, 33, 34, 66, 47, 30, 66, 66, 33, -2, 1, 34, -2, 18,
      33, 1, 31, 34, 2, 47, 32, -2, 63, 30, 17, -24, 34, 32, -25, 33, 49, 65, 30, 15, -2, 33, 31,
      -2, 31, 48, 1,
  };
  const std::vector<Index> corners = {  // three per face, 0-based
      0, 5, 6, 0, 6, 1, 1, 6, 7, 1, 7, 2, 2, 7, 8, 2, 8, 3, 3, 8, 9, 3, 9, 4, 5, 10, 11, 5, 11, 6,
      6, 11, 12, 6, 12, 7, 7, 12, 13, 7, 13, 8, 8, 13, 14, 8, 14, 9, 10, 15, 16, 10, 16, 11, 11, 16,
      17, 11, 17, 12, 12, 17, 18, 12, 18, 13, 13, 18, 19, 13, 19, 14, 15, 20, 21, 15, 21, 16, 16,
      21, 22, 16, 22, 17, 17, 22, 23, 17, 23, 18, 18, 23, 24, 18, 24, 19, 25, 31, 30, 25, 26, 31,
      26, 32, 31, 26, 27, 32, 27, 33, 32, 27, 28, 33, 28, 34, 33, 28, 29, 34, 30, 36, 35, 30, 31,
      36, 31, 37, 36, 31, 32, 37, 32, 38, 37, 32, 33, 38, 33, 39, 38, 33, 34, 39, 35, 41, 40, 35,
      36, 41, 36, 42, 41, 36, 37, 42, 37, 43, 42, 37, 38, 43, 38, 44, 43, 38, 39, 44, 40, 46, 45,
      40, 41, 46, 41, 47, 46, 41, 42, 47, 42, 48, 47, 42, 43, 48, 43, 49, 48, 43, 44, 49, 45, 46,
      51, 45, 51, 50, 50, 51, 21, 50, 21, 20, 46, 47, 52, 46, 52, 51, 51, 52, 22, 51, 22, 21, 47,
      48, 53, 47, 53, 52, 52, 53, 23, 52, 23, 22, 48, 49, 54, 48, 54, 53, 53, 54, 24, 53, 24, 23,
      25, 56, 26, 25, 55, 56, 55, 1, 56, 55, 0, 1, 26, 57, 27, 26, 56, 57, 56, 2, 57, 56, 1, 2, 27,
      58, 28, 27, 57, 58, 57, 3, 58, 57, 2, 3, 28, 59, 29, 28, 58, 59, 58, 4, 59, 58, 3, 4, 29, 59,
      60, 29, 60, 34, 34, 60, 61, 34, 61, 39, 39, 61, 62, 39, 62, 44, 44, 62, 54, 44, 54, 49, 59, 4,
      9, 59, 9, 60, 60, 9, 14, 60, 14, 61, 61, 14, 19, 61, 19, 62, 62, 19, 24, 62, 24, 54, 25, 63,
      55, 25, 30, 63, 30, 64, 63, 30, 35, 64, 35, 65, 64, 35, 40, 65, 40, 50, 65, 40, 45, 50, 55, 5,
      0, 55, 63, 5, 63, 10, 5, 63, 64, 10, 64, 15, 10, 64, 65, 15, 65, 20, 15, 65, 50, 20,
  };
  const Object o = scaled_literal(sixty_fourths, 64, corners, "folded");
  const std::vector<Vec3>& positions = o.positions;
  const std::vector<Face>& faces = o.topology->faces;
  ASSERT_TRUE(closed_and_oriented(o));
  // The fold: 93 = (28, 58, 59) and 96 = (29, 59, 60) meet away from 59 (an edge of one opposite
  // 59 meets the other: the two triangles' intersection, a segment from 59, ends on it).
  ASSERT_EQ(faces[93], (Face{28, 58, 59}));
  ASSERT_EQ(faces[96], (Face{29, 59, 60}));
  const Triangle t93 = o.triangle(93), t96 = o.triangle(96);
  EXPECT_TRUE(segment_triangle_intersection(positions[28], positions[58], t96).intersecting ||
              segment_triangle_intersection(positions[29], positions[60], t93).intersecting);
  const auto reference = run_pd(frame_of({o}));
  ASSERT_EQ(reference.size(), 1u);
  ASSERT_EQ(reference[0].status, PdStatus::Ok) << pd_status_name(reference[0].status);
  EXPECT_GT(reference[0].depth, 1.0);
  for (const auto& side : reference[0].inside_vertices) EXPECT_FALSE(std::count(side.begin(), side.end(), 59));
  // Each face of 59's star moved to the front in turn: the same entry (triangle ids mapped back).
  for (Index front : adjacency(*o.topology).vertex_triangles(59)) {
    SCOPED_TRACE("face " + std::to_string(front) + " first");
    std::vector<Index> order = {front};  // order[new id] = old id
    for (Index t = 0; t < o.num_triangles(); ++t)
      if (t != front) order.push_back(t);
    std::vector<Face> permuted;
    for (Index t : order) permuted.push_back(faces[static_cast<size_t>(t)]);
    const auto pd = run_pd(frame_of({literal_object(positions, permuted, "folded")}));
    ASSERT_EQ(pd.size(), 1u);
    ASSERT_EQ(pd[0].status, PdStatus::Ok) << pd_status_name(pd[0].status);
    EXPECT_EQ(pd[0].depth, reference[0].depth);
    EXPECT_EQ(pd[0].direction, reference[0].direction);
    EXPECT_EQ(pd[0].inside_vertices, reference[0].inside_vertices);
    EXPECT_EQ(pd[0].deepest_vertex, reference[0].deepest_vertex);
    for (int side = 0; side < 2; ++side) {
      std::vector<Index> mapped;
      for (Index t : pd[0].overlapping_triangles[static_cast<size_t>(side)]) mapped.push_back(order[static_cast<size_t>(t)]);
      std::sort(mapped.begin(), mapped.end());
      std::vector<Index> expected = reference[0].overlapping_triangles[static_cast<size_t>(side)];
      std::sort(expected.begin(), expected.end());
      EXPECT_EQ(mapped, expected);
    }
  }
}

TEST(PenetrationDepthSelf, EquallyDeepContactsGiveTheOneWithTheSmallestTriangle) {
  // Two copies of one overlapping box pair, 8 apart along x, as one object: two contacts of
  // exactly the same depth. The entry is the contact holding the smallest triangle id, in
  // either order of the copies.
  const Object a = make_box(Vec3::Zero(), Vec3::Ones(), 2, "a");
  const Object b = make_box(Vec3(0.75, 0.25, 0.125), Vec3(1, 0.5, 0.75), 1, "b");
  auto moved = [](Object o) {
    for (Vec3& p : o.positions) p.x() += 8;
    return o;
  };
  const auto near = run_pd(frame_of({a, b})), far = run_pd(frame_of({moved(a), moved(b)}));
  ASSERT_EQ(near.size(), 1u);
  ASSERT_EQ(far.size(), 1u);
  ASSERT_EQ(near[0].status, PdStatus::Ok);
  ASSERT_EQ(near[0].depth, far[0].depth);  // the tie
  const Index pair_triangles = a.num_triangles() + b.num_triangles();
  for (bool near_first : {true, false}) {
    SCOPED_TRACE(near_first ? "near copy first" : "far copy first");
    const Object m = near_first ? merge({a, b, moved(a), moved(b)}, "m") : merge({moved(a), moved(b), a, b}, "m");
    const auto pd = run_pd(frame_of({m}));
    ASSERT_EQ(pd.size(), 1u);
    ASSERT_EQ(pd[0].status, PdStatus::Ok) << pd_status_name(pd[0].status);
    EXPECT_EQ(pd[0].depth, near[0].depth);
    for (const auto& side : pd[0].overlapping_triangles) {
      ASSERT_FALSE(side.empty());
      for (Index t : side) EXPECT_LT(t, pair_triangles);
    }
    const double x = m.positions[static_cast<size_t>(pd[0].deepest_vertex)].x();
    EXPECT_EQ(x < 4, near_first) << x;
  }
}

TEST(PenetrationDepthSelf, UndefinedCasesGetAStatus) {
  const BoxPair bp = make_box_pair(0.15);
  {  // one face of A removed: open
    Object open = bp.bridged;
    auto topo = std::make_shared<Topology>(*open.topology);
    topo->faces.erase(topo->faces.begin());
    open.topology = topo;
    const auto pd = run_pd(frame_of({open}));
    ASSERT_EQ(pd.size(), 1u);
    EXPECT_EQ(pd[0].status, PdStatus::OpenSurface);
  }
  {  // one face flipped: not consistently oriented
    Object flipped = bp.bridged;
    auto topo = std::make_shared<Topology>(*flipped.topology);
    std::swap(topo->faces[5][1], topo->faces[5][2]);
    flipped.topology = topo;
    const auto pd = run_pd(frame_of({flipped}));
    ASSERT_EQ(pd.size(), 1u);
    EXPECT_EQ(pd[0].status, PdStatus::NonOrientable);
  }
  {  // a small box swallowed by a dented big one, both one object: too_deep
    Object big = make_box(Vec3::Zero(), Vec3::Constant(3), 2, "big");
    for (Vec3& p : big.positions)
      if (p == Vec3(1.5, 1.5, 3)) p = Vec3(1.5, 1.5, 1);
    const Object small = make_box(Vec3(1, 1, 0.5), Vec3::Ones(), 1, "small");
    const auto pd = run_pd(frame_of({merge({big, small}, "nested")}));
    ASSERT_EQ(pd.size(), 1u);
    EXPECT_EQ(pd[0].status, PdStatus::TooDeep) << pd_status_name(pd[0].status);
    // It lists what the two objects' entry lists: the inside vertices, and the intersecting
    // triangles with those touching an inside vertex (small's triangles touch only inside
    // vertices and intersect nothing but the dent).
    const auto twin = run_pd(frame_of({big, small}));
    ASSERT_EQ(twin.size(), 1u);
    EXPECT_EQ(twin[0].status, PdStatus::TooDeep);
    std::vector<Index> vertices = twin[0].inside_vertices[0], triangles = twin[0].overlapping_triangles[0];
    for (Index v : twin[0].inside_vertices[1]) vertices.push_back(v + big.num_vertices());
    for (Index t : twin[0].overlapping_triangles[1]) triangles.push_back(t + big.num_triangles());
    std::sort(vertices.begin(), vertices.end());
    std::sort(triangles.begin(), triangles.end());
    EXPECT_EQ(pd[0].inside_vertices[0], vertices);
    EXPECT_EQ(pd[0].overlapping_triangles[0], triangles);
    EXPECT_EQ(static_cast<Index>(twin[0].overlapping_triangles[1].size()), small.num_triangles());
  }
}

TEST(PenetrationDepth, NoIntersectionNoEntry) {
  const Frame frame = frame_of({make_box(Vec3::Zero(), Vec3::Ones(), 2, "a"), make_box(Vec3(1.01, 0, 0), Vec3::Ones(), 2, "b")});
  EXPECT_TRUE(run_pd(frame).empty());
}

}  // namespace
}  // namespace vproxq
