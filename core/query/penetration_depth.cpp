#include "core/query/penetration_depth.hpp"

#include "core/broad_phase/triangle_bvh.hpp"
#include "core/geometry/exact_distance.hpp"
#include "core/geometry/point_triangle.hpp"
#include "core/geometry/predicates.hpp"
#include "core/geometry/triangle_intersection.hpp"
#include "core/mesh/adjacency.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
#include <iterator>
#include <tuple>

namespace vproxq {
namespace {

// ---------------------------------------------------------------------------------------
// Inside test: exact signed ray crossings.
//
// The ray leaves p in +x. A triangle g = (a, b, c) whose projection on the yz plane has
// orientation s = sign(n.x) != 0 is crossed when p's projection lies inside g's projection
// and g's plane is ahead of p. Crossing a face whose normal points +x leaves the interior of
// an outward-oriented surface, so sum(s) over the crossed faces is the winding number.
// When p's projection falls on a projected edge or vertex, the ray is perturbed to
// p + (0, e, e^2) for an infinitesimal e > 0 (simulation of simplicity): each edge test then
// has a nonzero sign decided from exact coordinate comparisons, so of the faces sharing an
// edge exactly the right ones count, and a closed surface gives an exact integer. Faces
// parallel to the ray (s == 0) are never crossed by the perturbed ray.
// ---------------------------------------------------------------------------------------

/// Sign of the x component of (w - u) x (p' - u), p' = p + (0, e, e^2): orient2d in the yz
/// plane of the perturbed point.
int orient_yz_perturbed(const Vec3& u, const Vec3& w, const Vec3& p) {
  const int o = orient2d_projected(u, w, p, 0);
  if (o != 0) return o;
  // The perturbation adds (w-u).y * e^2 - (w-u).z * e: the e term decides unless it is 0.
  if (w.z() != u.z()) return w.z() > u.z() ? -1 : 1;
  if (w.y() != u.y()) return w.y() > u.y() ? 1 : -1;
  return 0;  // u and w project onto one point: the face's projection is flat (s == 0)
}

/// The signed crossing of triangle t by the ray from p: +1/-1, or 0 (missed). p must not lie
/// on t (callers test on_triangle() first): in t's plane and inside its closed projection, p
/// would be on t, so orient3d is then nonzero.
int ray_crossing(const Vec3& p, const Triangle& t) {
  const int s = orient2d_projected(t[0], t[1], t[2], 0);
  if (s == 0) return 0;
  for (int k = 0; k < 3; ++k)
    if (orient_yz_perturbed(t[static_cast<size_t>(k)], t[static_cast<size_t>((k + 1) % 3)], p) != s) return 0;
  const int above = orient3d(t[0], t[1], t[2], p);  // sign of n.(p - a) = n.x (p.x - plane.x)
  return above == -s ? s : 0;  // ahead of p iff p.x < plane.x iff sign(n.(p-a)) == -sign(n.x)
}

/// Whether p lies on the closed triangle t (exact; degenerate triangles as the point sets
/// they are).
bool on_triangle(const Vec3& p, const Triangle& t) {
  return segment_triangle_intersection(p, p, t).intersecting;
}

/// Winding number of `o` around p through its BVH: first whether p lies on a face (faces whose
/// box contains p), then the crossings of the faces whose box meets the ray. The perturbed ray
/// alone would see p on a face only when that face is not parallel to the ray and the
/// perturbation keeps p's projection in it; a point on a face in a y = const or z = const
/// plane, or on an edge the perturbation leaves, would get the winding number of a point next
/// to it, which is inside for faces on one side.
int winding_number(const Vec3& p, const Object& o, const TriangleBvh& bvh, bool& on_surface) {
  on_surface = false;
  AABB point;
  point.lo = point.hi = p;
  bvh.query(point, [] { return 0.0; }, [&](Index t, double) {
    on_surface = on_surface || on_triangle(p, o.triangle(t));
  });
  if (on_surface) return 0;
  AABB ray;
  ray.lo = p;
  ray.hi = Vec3(kInfinity, p.y(), p.z());
  int w = 0;
  bvh.query(ray, [] { return 0.0; }, [&](Index t, double) { w += ray_crossing(p, o.triangle(t)); });
  return w;
}

// ---------------------------------------------------------------------------------------
// Self-intersections: the winding number on a vertex's outward side.
//
// A vertex v of a closed, consistently oriented object O lies on O's own surface, so O's
// winding number w is not defined at v. Near v (closer than any face that does not contain
// v) the surface is v's star only, which splits a small ball around v into two sides: the
// outward side (the faces' normals point into it) with winding w_out, and the inward side
// with w_out + 1 (crossing a face against its normal enters one more time). w_out is what we
// need: it is the winding number of "the rest of O" at v, i.e. of the other sheets.
//
// It is computed exactly with the +x ray of winding_number(), cast from a symbolic point
//     q = v + eps (n1 - v) + eps^2 (n2 - v) + (0, e, e^2),   eps >> eps^2 >> e >> e^2 > 0,
// where f = (v, n1, n2) is a non-degenerate face of the star written from v in its own
// cyclic order: v + eps (n1 - v) + eps^2 (n2 - v) lies inside f next to v (barycentric
// 1 - eps - eps^2, eps, eps^2), and (0, e, e^2) is the ray perturbation used everywhere
// else. Every predicate is affine in its last point, so its sign at q is the first nonzero
// of: its value at v, at n1 (the eps term once the value at v is 0), at n2, then the e and
// e^2 terms of the ray perturbation - all exact orientation predicates on mesh points.
// Summing the signed crossings of every face except f gives the winding number just past f
// on the side that +x (or, for a face parallel to x, the perturbation) points to; that side
// is the outward one iff the first nonzero component of f's normal is positive. So
//     w_out = sum            if that component is positive,
//     w_out = sum - 1        otherwise.
// Only faces whose box meets the ray from v can be crossed (the faces near q contain v).
//
// A vertex is "inside another sheet" when w_out differs from its value at a vertex where
// the surface is single: for an outward-oriented closed surface that value is 0 (and w is
// 2 in a doubly covered region, -1 where a sheet folds inwards through another), for an
// inward-oriented one -1. The reference is taken per connected component of the mesh at
// its lexicographically largest vertex (largest x, then y, then z): every point of the
// component has x <= that vertex's x, so the ray from it leaves into the unbounded region
// (w = 0) and one of its two sides has w = 0: w_out there is 0 (outward) or -1 (inward).
// The reference counts only the component's own faces (another component may enclose the
// vertex). For two separate objects merged into one, w_out - reference is then exactly the
// other object's winding number, i.e. the inter-object inside test: the twin the tests
// check. (A vertex inside two other components of opposite orientations would cancel out;
// objects are not expected to nest like that.)
// ---------------------------------------------------------------------------------------

/// An object and the BVH of its triangles.
struct ObjectView {
  const Object* object;
  const TriangleBvh* bvh;
  double scale;  ///< the largest coordinate magnitude of the object's triangles (FrameBoxes)
};

/// The symbolic point q above, from v inside the star face (v, n1, n2).
struct StarPoint {
  Vec3 v, n1, n2;
};

/// Sign of orient2d_projected(u, w, q, 0) at the symbolic q (see above).
int orient_yz_star(const Vec3& u, const Vec3& w, const StarPoint& q) {
  for (const Vec3* p : {&q.v, &q.n1, &q.n2}) {
    if (*p == u || *p == w) continue;  // an end of the edge: exactly 0 (no exact fallback)
    const int o = orient2d_projected(u, w, *p, 0);
    if (o != 0) return o;
  }
  return orient_yz_perturbed(u, w, q.v);  // its value at v is 0: the perturbation decides
}

/// Sign of orient3d(t, q) at the symbolic q: the n . (q - t0) of ray_crossing().
int above_star(const Triangle& t, const StarPoint& q) {
  for (const Vec3* p : {&q.v, &q.n1, &q.n2}) {
    if (*p == t[0] || *p == t[1] || *p == t[2]) continue;  // a corner of t: exactly 0
    const int o = orient3d(t[0], t[1], t[2], *p);
    if (o != 0) return o;
  }
  // The perturbation (0, e, e^2) adds e n.y + e^2 n.z.
  const int ny = orient2d_projected(t[0], t[1], t[2], 1);
  return ny != 0 ? ny : orient2d_projected(t[0], t[1], t[2], 2);
}

/// ray_crossing() from the symbolic q. q never lies on t: t would then contain points next
/// to v, hence v, and either not be one of v's faces (v on another sheet) or cover f
/// coplanarly (star_is_covered()); outward_winding() rules out both before it casts.
int ray_crossing_star(const StarPoint& q, const Triangle& t) {
  const int s = orient2d_projected(t[0], t[1], t[2], 0);
  if (s == 0) return 0;
  for (int k = 0; k < 3; ++k)
    if (orient_yz_star(t[static_cast<size_t>(k)], t[static_cast<size_t>((k + 1) % 3)], q) != s) return 0;
  return above_star(t, q) == -s ? s : 0;
}

enum class VertexSide : std::uint8_t {
  Decided,       ///< w_out computed
  OnOtherSheet,  ///< v lies on a face that does not contain it (another sheet passes through v)
  FoldedStar,    ///< w_out depends on the star face it is read from: v's star folds through itself
  DegenerateStar,  ///< every face of the star is degenerate: undecided
  CoveredStar,     ///< a face of the star is covered coplanarly by another (folded flat): undecided
};

/// v's two other corners in face f, in f's cyclic order from v.
std::array<Index, 2> corners_after(const Face& f, Index v) {
  const int k = f[0] == v ? 0 : f[1] == v ? 1 : 2;
  return {f[static_cast<size_t>((k + 1) % 3)], f[static_cast<size_t>((k + 2) % 3)]};
}

/// Whether a face of v's star is covered coplanarly next to v by another face of the star
/// (the star folded flat): the symbolic point v + eps (n1 - v) + eps^2 (n2 - v) inside f =
/// (v, n1, n2) lies in the closed corner of g = (v, m1, m2) at v, g in f's plane. Decided in
/// the projection that keeps f's area, with exact orientations: the point is left of v->m1 and
/// right of v->m2 (as g's own orientation) when the first nonzero of each test's value at n1,
/// then at n2, has g's sign. (A face not containing v that covers f next to v contains v: such
/// a vertex lies on another sheet, tested before.)
bool star_is_covered(const Object& o, Index v, IndexSpan star) {
  const Vec3& p = o.positions[static_cast<size_t>(v)];
  for (Index f : star) {
    const Triangle tf = o.triangle(f);
    if (triangle_is_degenerate(tf)) continue;
    const auto [a1, a2] = corners_after(o.topology->faces[static_cast<size_t>(f)], v);
    const Vec3& n1 = o.positions[static_cast<size_t>(a1)];
    const Vec3& n2 = o.positions[static_cast<size_t>(a2)];
    int axis = 0;
    while (orient2d_projected(p, n1, n2, axis) == 0) ++axis;  // f has an area: some axis keeps it
    for (Index g : star) {
      if (g == f) continue;
      const Triangle tg = o.triangle(g);
      // Points that are corners of g, or equal to the other point of a test, give exactly 0
      // without calling the predicate (whose filter cannot certify a 0).
      auto on_plane = [&](const Vec3& x) {
        return x == tg[0] || x == tg[1] || x == tg[2] || orient3d(tg[0], tg[1], tg[2], x) == 0;
      };
      if (triangle_is_degenerate(tg) || !on_plane(n1) || !on_plane(n2)) continue;
      const auto [b1, b2] = corners_after(o.topology->faces[static_cast<size_t>(g)], v);
      const Vec3& m1 = o.positions[static_cast<size_t>(b1)];
      const Vec3& m2 = o.positions[static_cast<size_t>(b2)];
      auto orient = [&](const Vec3& x, const Vec3& y) { return x == y ? 0 : orient2d_projected(p, x, y, axis); };
      const int sg = orient(m1, m2);
      int left_of_m1 = orient(m1, n1);  // orient(v, m1, q)
      if (left_of_m1 == 0) left_of_m1 = orient(m1, n2);
      int right_of_m2 = orient(n1, m2);  // orient(v, q, m2)
      if (right_of_m2 == 0) right_of_m2 = orient(n2, m2);
      if (sg != 0 && left_of_m1 == sg && right_of_m2 == sg) return true;
    }
  }
  return false;
}

/// w_out of vertex v of `o` (see above), counting only the faces t with keep(t). It is read/// w_out of vertex v of `o` (see above), counting only the faces t with keep(t). It is read
/// from every non-degenerate face of v's star: where the star is an embedded disc near v, its
/// faces' outward sides are one region and agree. Where two of v's faces cross each other (the
/// star folds through itself; such faces share v, so the pair is not an intersecting pair), v
/// is an end of that crossing curve and the outward sides of its faces can lie in regions of
/// different winding: like a vertex on another face, v then lies on the curve (FoldedStar).
template <typename Keep>
VertexSide outward_winding(const ObjectView& view, Index v, const Keep& keep, int& w_out) {
  const Object& o = *view.object;
  const Vec3& p = o.positions[static_cast<size_t>(v)];
  auto has_v = [&](Index t) {
    const Face& f = o.topology->faces[static_cast<size_t>(t)];
    return f[0] == v || f[1] == v || f[2] == v;
  };
  // Another sheet through v: w_out is then not a property of v's neighbourhood. Such a
  // vertex lies on the intersection curve; like a vertex on the other object's surface in
  // the inter-object walk, it counts as not inside.
  bool on = false;
  AABB point;
  point.lo = point.hi = p;
  view.bvh->query(point, [] { return 0.0; }, [&](Index t, double) {
    if (!on && !has_v(t) && keep(t)) on = segment_triangle_intersection(p, p, o.triangle(t)).intersecting;
  });
  if (on) return VertexSide::OnOtherSheet;
  const Adjacency& adj = adjacency(*o.topology);
  if (star_is_covered(o, v, adj.vertex_triangles(v))) return VertexSide::CoveredStar;
  // The faces the ray from v can cross (the faces near the symbolic point contain v).
  AABB ray;
  ray.lo = p;
  ray.hi = Vec3(kInfinity, p.y(), p.z());
  std::vector<Index> candidates;
  view.bvh->query(ray, [] { return 0.0; }, [&](Index t, double) {
    if (keep(t)) candidates.push_back(t);
  });
  bool any = false, folded = false;
  for (Index face : adj.vertex_triangles(v)) {
    const Triangle tf = o.triangle(face);
    if (triangle_is_degenerate(tf)) continue;
    const auto [n1, n2] = corners_after(o.topology->faces[static_cast<size_t>(face)], v);
    const StarPoint q{p, o.positions[static_cast<size_t>(n1)], o.positions[static_cast<size_t>(n2)]};
    int sum = 0;
    for (Index t : candidates)
      if (t != face) sum += ray_crossing_star(q, o.triangle(t));
    int side = 0;
    for (int axis = 0; axis < 3 && side == 0; ++axis) side = orient2d_projected(tf[0], tf[1], tf[2], axis);
    const int w = side > 0 ? sum : sum - 1;
    folded = folded || (any && w != w_out);
    w_out = w;
    any = true;
  }
  if (!any) return VertexSide::DegenerateStar;
  return folded ? VertexSide::FoldedStar : VertexSide::Decided;
}

/// Disjoint sets over 0..n-1 (path halving; the smaller root wins, so roots are canonical).
struct DisjointSets {
  std::vector<Index> parent;
  explicit DisjointSets(size_t n) : parent(n) {
    for (size_t k = 0; k < n; ++k) parent[k] = static_cast<Index>(k);
  }
  Index find(Index a) {
    while (parent[static_cast<size_t>(a)] != a) {
      parent[static_cast<size_t>(a)] = parent[static_cast<size_t>(parent[static_cast<size_t>(a)])];
      a = parent[static_cast<size_t>(a)];
    }
    return a;
  }
  void unite(Index a, Index b) {
    a = find(a);
    b = find(b);
    if (a != b) parent[static_cast<size_t>(std::max(a, b))] = std::min(a, b);
  }
};

/// What a self-intersecting object needs across its contacts: the w_out of a single-sheet
/// vertex of each connected component of the mesh, computed when first needed.
struct SelfContext {
  const ObjectView* view = nullptr;
  std::vector<Index> component;  ///< per vertex: the component's root
  std::vector<Index> top;        ///< per root: the lexicographically largest vertex
  std::vector<int> reference;    ///< per root: its w_out; kUnset, or kUndecided
  /// Per root: whether an intersecting pair of the object has both triangles in the component.
  std::vector<char> crosses_itself;
  static constexpr int kUnset = 1 << 30, kUndecided = kUnset + 1;

  explicit SelfContext(const ObjectView& v) : view(&v) {
    const Object& o = *v.object;
    const size_t n = static_cast<size_t>(o.num_vertices());
    DisjointSets sets(n);
    for (const Face& f : o.topology->faces) {
      sets.unite(f[0], f[1]);
      sets.unite(f[0], f[2]);
    }
    component.resize(n);
    top.assign(n, kNoIndex);
    reference.assign(n, kUnset);
    auto larger = [&](Index a, Index b) {  // lexicographic on (x, y, z), then the id
      const Vec3& pa = o.positions[static_cast<size_t>(a)];
      const Vec3& pb = o.positions[static_cast<size_t>(b)];
      return std::tie(pa.x(), pa.y(), pa.z(), a) > std::tie(pb.x(), pb.y(), pb.z(), b);
    };
    for (size_t k = 0; k < n; ++k) {
      const Index r = sets.find(static_cast<Index>(k));
      component[k] = r;
      Index& t = top[static_cast<size_t>(r)];
      if (t == kNoIndex || larger(static_cast<Index>(k), t)) t = static_cast<Index>(k);
    }
  }

  /// The component's root of triangle t.
  Index component_of_triangle(Index t) const {
    return component[static_cast<size_t>(view->object->topology->faces[static_cast<size_t>(t)][0])];
  }

  /// Marks the components in which the object's intersecting pairs [first, last) cross.
  void mark_crossings(std::vector<IntersectingPair>::const_iterator first,
                      std::vector<IntersectingPair>::const_iterator last) {
    crosses_itself.assign(component.size(), 0);
    for (auto it = first; it != last; ++it) {
      const Index r = component_of_triangle(it->tri_a);
      if (r == component_of_triangle(it->tri_b)) crosses_itself[static_cast<size_t>(r)] = 1;
    }
  }

  /// The vertex whose w_out reference_of(v) reads: the largest of v's component.
  Index reference_vertex(Index v) const { return top[static_cast<size_t>(component[static_cast<size_t>(v)])]; }

  /// w_out of a single-sheet vertex of v's component (0 or -1), or kUndecided.
  int reference_of(Index v) {
    const Index r = component[static_cast<size_t>(v)];
    int& ref = reference[static_cast<size_t>(r)];
    if (ref == kUnset) {
      int w = 0;
      const Object& o = *view->object;
      auto own = [&](Index t) {
        return component[static_cast<size_t>(o.topology->faces[static_cast<size_t>(t)][0])] == r;
      };
      const VertexSide s = outward_winding(*view, top[static_cast<size_t>(r)], own, w);
      ref = (s == VertexSide::Decided && (w == 0 || w == -1)) ? w : kUndecided;
    }
    return ref;
  }
};

// ---------------------------------------------------------------------------------------
// Surface checks: the interior is defined when every edge is used by exactly two faces, once
// in each direction (closed, manifold, consistently oriented).
// ---------------------------------------------------------------------------------------

PdStatus surface_status(const Topology& topo) {
  const Adjacency& adj = adjacency(topo);
  bool open = false, non_manifold = false, non_orientable = false;
  for (Index e = 0; e < static_cast<Index>(adj.edges().size()); ++e) {
    const auto& ab = adj.edges()[static_cast<size_t>(e)];
    int forward = 0, backward = 0;
    for (Index t : adj.edge_triangles(e)) {
      const Face& f = topo.faces[static_cast<size_t>(t)];
      for (int k = 0; k < 3; ++k) {
        const Index u = f[static_cast<size_t>(k)], w = f[static_cast<size_t>((k + 1) % 3)];
        forward += (u == ab[0] && w == ab[1]);
        backward += (u == ab[1] && w == ab[0]);
      }
    }
    if (forward + backward == 1) open = true;
    else if (forward + backward > 2) non_manifold = true;
    else if (forward != backward) non_orientable = true;
  }
  if (open) return PdStatus::OpenSurface;
  if (non_manifold) return PdStatus::NonManifold;
  if (non_orientable) return PdStatus::NonOrientable;
  return PdStatus::Ok;
}

// ---------------------------------------------------------------------------------------
// Intersection of two triangles known to intersect: the vertices of the common segment (or
// polygon, for coplanar triangles), approximately. These are the vertices of the overlap
// region's boundary that are not vertices of either mesh.
// ---------------------------------------------------------------------------------------

/// Keeps the part of a convex polygon (or segment, or point) in the half-space
/// {x : (x - origin) . normal >= 0} (Sutherland–Hodgman).
std::vector<Vec3> clip(const std::vector<Vec3>& poly, const Vec3& origin, const Vec3& normal) {
  std::vector<Vec3> out;
  const size_t n = poly.size();
  if (n == 0) return out;
  if (n == 1) {
    if ((poly[0] - origin).dot(normal) >= 0) out.push_back(poly[0]);
    return out;
  }
  const size_t edges = n == 2 ? 1 : n;  // a segment is not closed
  for (size_t k = 0; k < edges; ++k) {
    const Vec3& p = poly[k];
    const Vec3& q = poly[(k + 1) % n];
    const double dp = (p - origin).dot(normal), dq = (q - origin).dot(normal);
    if (dp >= 0) out.push_back(p);
    if ((dp < 0 && dq > 0) || (dp > 0 && dq < 0)) out.push_back(p + (q - p) * (dp / (dp - dq)));
    if (n == 2 && dq >= 0) out.push_back(q);
  }
  return out;
}

void intersection_vertices(const Triangle& f, const Triangle& g, std::vector<Vec3>& out) {
  const size_t before = out.size();
  if (!triangle_is_degenerate(f) && !triangle_is_degenerate(g)) {
    const Vec3 ng = (g[1] - g[0]).cross(g[2] - g[0]);
    int side[3];
    double dist[3];
    for (int k = 0; k < 3; ++k) {
      side[k] = orient3d(g[0], g[1], g[2], f[static_cast<size_t>(k)]);
      dist[k] = side[k] == 0 ? 0.0 : ng.dot(f[static_cast<size_t>(k)] - g[0]);
    }
    std::vector<Vec3> piece;  // f ∩ plane(g): f itself when coplanar, else a segment or point
    if (side[0] == 0 && side[1] == 0 && side[2] == 0) {
      piece = {f[0], f[1], f[2]};
    } else {
      for (int k = 0; k < 3; ++k) {
        const int l = (k + 1) % 3;
        if (side[k] == 0) piece.push_back(f[static_cast<size_t>(k)]);
        if (side[k] * side[l] < 0)
          piece.push_back(f[static_cast<size_t>(k)] + (f[static_cast<size_t>(l)] - f[static_cast<size_t>(k)]) *
                                                          (dist[k] / (dist[k] - dist[l])));
      }
      if (piece.size() > 2) piece.resize(2);  // a vertex on the plane and the crossing coincide
    }
    for (int k = 0; k < 3 && !piece.empty(); ++k) {
      const Vec3& a = g[static_cast<size_t>(k)];
      const Vec3 inward = ng.cross(g[static_cast<size_t>((k + 1) % 3)] - a);
      piece = clip(piece, a, inward);
    }
    out.insert(out.end(), piece.begin(), piece.end());
  }
  if (out.size() == before) {
    // Degenerate triangles, or rounding lost a sliver: one exact common point per edge.
    for (int k = 0; k < 3; ++k) {
      const auto r = segment_triangle_intersection(f[static_cast<size_t>(k)], f[static_cast<size_t>((k + 1) % 3)], g);
      if (r.intersecting) out.push_back(r.point);
      const auto s = segment_triangle_intersection(g[static_cast<size_t>(k)], g[static_cast<size_t>((k + 1) % 3)], f);
      if (s.intersecting) out.push_back(s.point);
    }
  }
}

// ---------------------------------------------------------------------------------------
// The local walk.
// ---------------------------------------------------------------------------------------

struct Walk {
  std::vector<Index> inside;                    ///< ascending
  std::vector<std::vector<Index>> components;   ///< the vertices of each flood, ascending
  bool swallowed = false;     ///< some connected set of inside vertices has no outside neighbour
};

/// Vertices of `oa` for which inside(v) holds, connected to the vertices of the seed
/// triangles through such vertices; inside() is called at most once per vertex.
template <typename Inside>
Walk walk_from(const Object& oa, const std::vector<Index>& seed_triangles, const Inside& inside) {
  const Adjacency& adj = adjacency(*oa.topology);
  enum : std::int8_t { kUnknown = 0, kInside = 1, kOutside = 2 };
  std::vector<std::int8_t> state(static_cast<size_t>(oa.num_vertices()), kUnknown);
  auto classify = [&](Index v) { state[static_cast<size_t>(v)] = inside(v) ? kInside : kOutside; };
  Walk walk;
  std::deque<Index> queue;
  std::vector<Index> seeds;
  for (Index t : seed_triangles)
    for (Index v : oa.topology->faces[static_cast<size_t>(t)]) seeds.push_back(v);
  std::sort(seeds.begin(), seeds.end());
  seeds.erase(std::unique(seeds.begin(), seeds.end()), seeds.end());
  for (Index s : seeds) {
    if (state[static_cast<size_t>(s)] == kUnknown) classify(s);
  }
  // Each seed still unexpanded starts a flood over one connected set of inside vertices.
  std::vector<char> expanded(static_cast<size_t>(oa.num_vertices()), 0);
  for (Index s : seeds) {
    if (state[static_cast<size_t>(s)] != kInside || expanded[static_cast<size_t>(s)]) continue;
    bool meets_outside = false;
    std::vector<Index> component;
    queue.push_back(s);
    expanded[static_cast<size_t>(s)] = 1;
    while (!queue.empty()) {
      const Index v = queue.front();
      queue.pop_front();
      component.push_back(v);
      for (Index t : adj.vertex_triangles(v))
        for (Index u : oa.topology->faces[static_cast<size_t>(t)]) {
          if (state[static_cast<size_t>(u)] == kUnknown) classify(u);
          if (state[static_cast<size_t>(u)] == kOutside) {
            meets_outside = true;
          } else if (!expanded[static_cast<size_t>(u)]) {
            expanded[static_cast<size_t>(u)] = 1;
            queue.push_back(u);
          }
        }
    }
    if (!meets_outside) walk.swallowed = true;
    std::sort(component.begin(), component.end());
    walk.inside.insert(walk.inside.end(), component.begin(), component.end());
    walk.components.push_back(std::move(component));
  }
  std::sort(walk.inside.begin(), walk.inside.end());
  return walk;
}

/// Vertices of `a` inside `b`, connected to the seeds through inside vertices.
Walk walk_inside(const ObjectView& a, const ObjectView& b, const std::vector<Index>& seed_triangles) {
  const Object& oa = *a.object;
  return walk_from(oa, seed_triangles, [&](Index v) {
    bool on = false;
    const int w = winding_number(oa.positions[static_cast<size_t>(v)], *b.object, *b.bvh, on);
    // On the other surface counts as outside: such a vertex is a vertex of an intersection
    // segment, which the depth takes into account anyway.
    return !on && w != 0;
  });
}

/// p's nearest point on an object's surface: its computed distance, the point, and the
/// triangle it lies on (kNoIndex: none).
struct Nearest {
  double distance = kInfinity;
  Vec3 point = Vec3::Zero();
  Index triangle = kNoIndex;
};

/// An exact squared point-triangle distance, computed when first needed (exact arithmetic is
/// slow, and only near ties need it).
class LazyExact {
 public:
  LazyExact() = default;
  LazyExact(const Vec3& p, const Triangle& t) : p_(p), t_(t) {}
  const ExactFraction& value() {
    if (!done_) {
      value_ = exact_point_triangle_squared_distance(p_, t_);
      done_ = true;
    }
    return value_;
  }

 private:
  Vec3 p_ = Vec3::Zero();
  Triangle t_{};
  ExactFraction value_;
  bool done_ = false;
};

/// sign(a - b) for two squared point-triangle distances whose computed distances are da and
/// db: computed distances farther apart than `slack` decide it (slack is far above the
/// rounding of point_triangle_distance: see pd_slack); nearer ones, in particular exact ties,
/// are decided in exact arithmetic.
int compare_distances(double da, LazyExact& a, double db, LazyExact& b, double slack) {
  if (da < db - slack) return -1;
  if (da > db + slack) return 1;
  return compare(a.value(), b.value());
}

/// The slack of compare_distances for points and triangles of objects whose coordinates are
/// at most `scale` in magnitude: 2^-40 scale, thousands of times the 16 e*scale that bounds
/// the error of a computed point-triangle distance (docs/algorithms.md, "Exactness"), so that two computed
/// distances more than the slack apart are ordered as the exact ones are.
double pd_slack(double scale) { return 0x1p-40 * scale; }

/// p's nearest point on `o`'s surface, leaving out the triangles t with skip(t): the triangle
/// of the exactly smallest distance (ties: the smallest id); none when every triangle is left
/// out. With `stop_below` >= 0, the search may stop at a triangle whose distance is less than
/// stop_below by more than the slack: its computed distance is then returned, for a caller
/// that only needs to know that p's exact distance is less than that of a point at stop_below.
template <typename Skip>
Nearest nearest_point(const Vec3& p, const ObjectView& o, double slack, const Skip& skip, double stop_below = -1) {
  Nearest best;
  LazyExact best_exact;
  bool stopped = false;
  AABB box;
  box.lo = box.hi = p;
  o.bvh->query(
      box, [&] { return best.distance + slack; },
      [&](Index t, double d2) {
        const double reach = best.distance + slack;
        if (stopped || d2 > reach * reach || skip(t)) return;
        const Triangle tri = o.object->triangle(t);
        const PointTriangleResult r = point_triangle_distance(p, tri);
        const double d = std::sqrt(r.squared_distance);
        LazyExact exact(p, tri);
        if (best.triangle != kNoIndex) {
          const int c = compare_distances(d, exact, best.distance, best_exact, slack);
          if (c > 0 || (c == 0 && t > best.triangle)) return;
        }
        best = {d, r.closest, t};
        best_exact = std::move(exact);
        stopped = stop_below >= 0 && best.distance < stop_below - slack;
      },
      [&](std::int32_t) { return stopped; });
  return best;
}

/// The deepest vertex so far, and whether p at its nearest point `n` on `other` is strictly
/// deeper (exactly; ties keep the earlier vertex).
struct Deepest {
  Nearest nearest;
  LazyExact exact;
  bool found = false;

  /// Whether p, whose nearest point is n, is deeper than the deepest so far (exactly); with
  /// `on_tie`, also where they are exactly as deep.
  bool deeper(const Vec3& p, const Nearest& n, const Object& other, double slack, bool on_tie = false) {
    if (n.triangle == kNoIndex) return false;
    if (!found) return true;
    LazyExact candidate(p, other.triangle(n.triangle));
    const int order = compare_distances(n.distance, candidate, nearest.distance, exact, slack);
    return order > 0 || (on_tie && order == 0);
  }
  void take(const Vec3& p, const Nearest& n, const Object& other) {
    nearest = n;
    exact = LazyExact(p, other.triangle(n.triangle));
    found = true;
  }
};

/// max - min of the projections of the points on the unit vector u.
double width(const std::vector<Vec3>& points, const Vec3& u) {
  double lo = kInfinity, hi = -kInfinity;
  for (const Vec3& p : points) {
    const double x = p.dot(u);
    lo = std::min(lo, x);
    hi = std::max(hi, x);
  }
  return points.empty() ? 0.0 : hi - lo;
}

std::vector<Index> overlapping_triangles(const Object& o, const std::vector<Index>& intersecting,
                                         const std::vector<Index>& inside) {
  std::vector<Index> out = intersecting;
  const Adjacency& adj = adjacency(*o.topology);
  for (Index v : inside)
    for (Index t : adj.vertex_triangles(v)) out.push_back(t);
  std::sort(out.begin(), out.end());
  out.erase(std::unique(out.begin(), out.end()), out.end());
  return out;
}

/// Completes an entry whose direction holds the deepest pair's vector (`best` its length, 0
/// when no vertex lies strictly inside): the unit direction T and the depth, the width of
/// `points` along T. With no vertex strictly inside (a shallow overlap, or faces lying on each
/// other, as for two boxes sliding into each other face to face) the paper's distance pairs are
/// all 0: T is then the overlapping face normal along which the overlap is narrowest (for a
/// convex overlap, a facet normal is a candidate minimal translation direction), times
/// `sign[side]` so that it points the way objects[0]'s side must move; Shallow when every
/// overlapping face is degenerate. The same where the deepest vertex's nearest point is
/// computed on the vertex itself (its distance, though not 0, is below the rounding of the
/// coordinates, so every inside vertex lies within rounding of the other surface): its
/// vector gives no direction.
PenetrationDepth finish_depth(PenetrationDepth& pd, double best, const std::vector<Vec3>& points,
                              const std::array<const Object*, 2>& owner,
                              const std::array<double, 2>& sign) {
  const double length = pd.direction.norm();
  if (best > 0 && length > 0) {
    pd.direction /= length;
    pd.depth = width(points, pd.direction);
    pd.status = PdStatus::Ok;
    return pd;
  }
  pd.deepest_object = pd.deepest_vertex = kNoIndex;
  pd.deepest_point = pd.nearest_point = Vec3::Zero();
  double narrowest = kInfinity;
  for (size_t side = 0; side < 2; ++side)
    for (Index t : pd.overlapping_triangles[side]) {
      const Triangle tri = owner[side]->triangle(t);
      Vec3 n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
      const double len = n.norm();
      if (!(len > 0)) continue;
      n /= len;
      const double w = width(points, n);
      if (w < narrowest) {
        narrowest = w;
        pd.direction = sign[side] * n;
      }
    }
  if (narrowest == kInfinity) {
    pd.status = PdStatus::Shallow;
    pd.direction = Vec3::Zero();
    return pd;
  }
  pd.depth = narrowest;
  pd.status = PdStatus::Ok;
  return pd;
}

// ---------------------------------------------------------------------------------------
// Self-intersections: the local walk within one object.
//
// A contact is a connected set of intersecting pairs of the object: pairs are linked when
// they share a triangle or their triangles share a vertex. Per contact:
//  - the walk (as between objects) starts at the vertices of the contact's triangles and
//    floods through vertices inside another sheet (w_out != reference, see above); each flood
//    is one connected set of inside vertices C, i.e. one piece of sheet pushed into another
//    sheet, bounded by the intersection curve. A flood without an outside neighbour: too_deep.
//  - the vertex's own sheet near the contact, R(C): the triangles touching C, and from those
//    that intersect nothing a flood across edges through triangles that intersect nothing.
//    The triangles the curve runs through are included where the flood meets them, but not
//    crossed: the curve bounds R(C). From those, R(C) follows the curve: across an edge that
//    meets a triangle they intersect (the curve passes through that edge) to the triangles
//    beyond it, which are the same sheet. If R(C) holds both triangles of an intersecting pair,
//    the curve does not separate the two sheets there (e.g. a triangle-sized fold): the
//    contact is undecided (status self_intersection).
//  - T: for each v in C, its nearest point on the object outside R(C), i.e. on the sheet(s)
//    across the curve; the pair of maximal distance gives T, the translation of the deepest
//    vertex's sheet that brings it out. Where C's mesh component crosses no part of itself,
//    the whole component is excluded with R(C): it is one sheet. Leaving in triangles of the
//    vertex's own side beyond the curve is harmless when they lie outside the other sheet:
//    the segment from v (inside it) to such a point crosses the other sheet first, at a
//    nearer point; not so for a piece inside the other sheet that R(C) does not reach.
//  - depth: the width along T of all inside vertices of the contact and of the vertices of
//    its intersection segments, as between objects.
// For two objects merged into one without a bridge this is the inter-object computation:
// the inside vertices are the same, and the nearest point lies on the other object (its
// component). With a bridge elsewhere, R(C) is the vertex's own object's part near the
// contact.
// ---------------------------------------------------------------------------------------

/// PD of one self-intersection contact of the object of `view` (pairs [first, last) of it).
PenetrationDepth self_contact_depth(SelfContext& ctx, Index object, const std::vector<IntersectingPair>& pairs,
                                    std::vector<int>& stamp, int& next_stamp) {
  const ObjectView& view = *ctx.view;
  const Object& o = *view.object;
  const Adjacency& adj = adjacency(*o.topology);
  PenetrationDepth pd;
  pd.objects = {object, object};
  std::vector<Index> hit;  // the contact's intersecting triangles
  for (const IntersectingPair& p : pairs) {
    hit.push_back(p.tri_a);
    hit.push_back(p.tri_b);
  }
  std::sort(hit.begin(), hit.end());
  hit.erase(std::unique(hit.begin(), hit.end()), hit.end());
  auto is_hit = [&](Index t) { return std::binary_search(hit.begin(), hit.end(), t); };
  pd.overlapping_triangles = {hit, {}};
  // (triangle, a triangle it intersects), both ways, sorted.
  std::vector<std::pair<Index, Index>> partners;
  for (const IntersectingPair& p : pairs) {
    partners.emplace_back(p.tri_a, p.tri_b);
    partners.emplace_back(p.tri_b, p.tri_a);
  }
  std::sort(partners.begin(), partners.end());

  bool undecided = false;
  // The reason given is that of the smallest undecided vertex of the walk (each counts as not
  // inside, so which vertices the walk classifies does not depend on the order it meets them).
  Index undecided_vertex = kNoIndex;
  const Walk walk = walk_from(o, hit, [&](Index v) {
    const int ref = ctx.reference_of(v);
    int w = 0;
    const VertexSide s = outward_winding(view, v, [](Index) { return true; }, w);
    const bool ref_undecided = ref == SelfContext::kUndecided;
    if (ref_undecided || s == VertexSide::DegenerateStar || s == VertexSide::CoveredStar) {
      undecided = true;
      if (undecided_vertex == kNoIndex || v < undecided_vertex) {
        undecided_vertex = v;
        pd.reason = ref_undecided ? PdReason::ReferenceVertex
                    : s == VertexSide::DegenerateStar ? PdReason::DegenerateStar
                                                      : PdReason::FlatFold;
        pd.reason_features = {ref_undecided ? ctx.reference_vertex(v) : v, kNoIndex};
      }
      return false;
    }
    return s == VertexSide::Decided && w != ref;
  });
  if (undecided) {
    pd.status = PdStatus::SelfIntersection;
    return pd;
  }
  if (walk.swallowed) {  // as between objects: the inside vertices and step 2's triangles
    pd.inside_vertices = {walk.inside, {}};
    pd.overlapping_triangles = {overlapping_triangles(o, hit, walk.inside), {}};
    pd.status = PdStatus::TooDeep;
    return pd;
  }

  // Own sheet R(C) of each inside component, nearest points outside it.
  const double slack = pd_slack(view.scale);
  Deepest deepest;
  size_t deepest_component = 0;
  std::vector<std::vector<Index>> touching(walk.components.size());  // triangles touching C
  std::vector<std::vector<Index>> region_hits(walk.components.size());
  for (size_t c = 0; c < walk.components.size(); ++c) {
    const int mark = next_stamp++;
    auto in_region = [&](Index t) { return stamp[static_cast<size_t>(t)] == mark; };
    std::vector<Index> stack;
    auto add = [&](Index t) {
      if (in_region(t)) return;
      stamp[static_cast<size_t>(t)] = mark;
      if (is_hit(t)) region_hits[c].push_back(t);
      else stack.push_back(t);
    };
    for (Index v : walk.components[c])
      for (Index t : adj.vertex_triangles(v)) {
        touching[c].push_back(t);
        add(t);
      }
    while (!stack.empty()) {
      const Index t = stack.back();
      stack.pop_back();
      for (Index e : adj.triangle_edges(t)) {
        if (e == kNoIndex) continue;
        for (Index u : adj.edge_triangles(e)) add(u);
      }
    }
    // Along the curve: an edge of an intersecting triangle of R(C) that meets a triangle the
    // intersecting triangle meets carries the curve over to the triangles beyond it, which
    // hold the same sheet's continuation (an edge whose two ends are outside the other sheet
    // can still pass through it in its middle: the sheet's part inside then runs on across
    // it). They join R(C), without being crossed themselves in the flood above.
    for (size_t k = 0; k < region_hits[c].size(); ++k) {
      const Index t = region_hits[c][k];
      const auto [lo, hi] = std::equal_range(partners.begin(), partners.end(), std::pair<Index, Index>{t, kNoIndex},
                                             [](const auto& x, const auto& y) { return x.first < y.first; });
      for (Index e : adj.triangle_edges(t)) {
        if (e == kNoIndex) continue;
        const auto& ends = adj.edges()[static_cast<size_t>(e)];
        const Vec3& p0 = o.positions[static_cast<size_t>(ends[0])];
        const Vec3& p1 = o.positions[static_cast<size_t>(ends[1])];
        bool carries = false;
        for (auto it = lo; it != hi && !carries; ++it)
          carries = segment_triangle_intersection(p0, p1, o.triangle(it->second)).intersecting;
        if (!carries) continue;
        for (Index u : adj.edge_triangles(e))
          if (!in_region(u)) {
            stamp[static_cast<size_t>(u)] = mark;
            region_hits[c].push_back(u);
          }
      }
    }
    for (const IntersectingPair& p : pairs)
      if (in_region(p.tri_a) && in_region(p.tri_b)) {
        undecided = true;
        pd.reason = PdReason::SheetsNotSeparated;
        pd.reason_features = {p.tri_a, p.tri_b};
        break;
      }
    if (undecided) break;
    std::sort(touching[c].begin(), touching[c].end());
    touching[c].erase(std::unique(touching[c].begin(), touching[c].end()), touching[c].end());
    std::sort(region_hits[c].begin(), region_hits[c].end());
    // A mesh component that crosses no part of itself is one sheet: all of it is C's own
    // sheet, and the other sheets are other components (R(C) alone can leave out a piece of
    // it that lies inside the other sheet, cut off by the curve and nearer to v than the other
    // sheet's surface: a jittered box's vertex inside a tetrahedron, tests/fuzz/seeds/pd).
    const Index own_component = ctx.component[static_cast<size_t>(walk.components[c].front())];
    const bool whole_component = !ctx.crosses_itself[static_cast<size_t>(own_component)];
    auto own_sheet = [&](Index t) {
      return in_region(t) || (whole_component && ctx.component_of_triangle(t) == own_component);
    };
    for (Index v : walk.components[c]) {
      const Vec3& p = o.positions[static_cast<size_t>(v)];
      const Nearest near = nearest_point(p, view, slack, own_sheet);
      if (near.triangle == kNoIndex) {  // the own sheet is the whole object
        undecided = true;
        pd.reason = PdReason::WholeObject;
        pd.reason_features = {v, kNoIndex};
        break;
      }
      // Ties: the smallest vertex id (the floods come in the order of their first seed
      // vertex, each ascending, so a later flood can hold a smaller id).
      if (deepest.deeper(p, near, o, slack, v < pd.deepest_vertex)) {
        deepest.take(p, near, o);
        deepest_component = c;
        pd.deepest_object = object;
        pd.deepest_vertex = v;
        pd.deepest_point = p;
        pd.nearest_point = near.point;
        pd.direction = near.point - p;
      }
    }
    if (undecided) break;
  }
  if (undecided) {
    pd.deepest_object = pd.deepest_vertex = kNoIndex;
    pd.deepest_point = pd.nearest_point = pd.direction = Vec3::Zero();
    pd.inside_vertices = {walk.inside, {}};
    pd.status = PdStatus::SelfIntersection;
    return pd;
  }

  // Features: side 0 is the deepest vertex's piece of sheet (its inside vertices, the
  // triangles touching them and the intersecting triangles bounding it), side 1 the rest.
  std::array<std::vector<Index>, 2> verts, tris;
  for (size_t c = 0; c < walk.components.size(); ++c) {
    const size_t side = c == deepest_component ? 0 : 1;
    verts[side].insert(verts[side].end(), walk.components[c].begin(), walk.components[c].end());
    if (side == 0) {
      // R(C)'s intersecting triangles: the curve's way across an edge can also reach a
      // triangle that intersects nothing listed (it meets the other sheet only where it shares
      // a vertex with it, e.g. along a box edge a vertex was moved onto), which is no
      // overlapping triangle (docs/algorithms.md, "Local penetration depth", step 2).
      std::vector<Index> bounding;
      std::copy_if(region_hits[c].begin(), region_hits[c].end(), std::back_inserter(bounding), is_hit);
      std::set_union(touching[c].begin(), touching[c].end(), bounding.begin(), bounding.end(),
                     std::back_inserter(tris[0]));
    } else {
      tris[1].insert(tris[1].end(), touching[c].begin(), touching[c].end());
    }
  }
  if (walk.components.empty()) {  // nothing inside: split the pairs' triangles by position
    for (const IntersectingPair& p : pairs) {
      tris[0].push_back(p.tri_a);
      tris[1].push_back(p.tri_b);
    }
  } else {
    tris[1].insert(tris[1].end(), hit.begin(), hit.end());
  }
  for (int side = 0; side < 2; ++side) {
    auto& t = tris[static_cast<size_t>(side)];
    std::sort(t.begin(), t.end());
    t.erase(std::unique(t.begin(), t.end()), t.end());
    std::sort(verts[static_cast<size_t>(side)].begin(), verts[static_cast<size_t>(side)].end());
  }
  std::vector<Index> rest;
  std::set_difference(tris[1].begin(), tris[1].end(), tris[0].begin(), tris[0].end(), std::back_inserter(rest));
  tris[1] = std::move(rest);
  pd.inside_vertices = verts;
  pd.overlapping_triangles = tris;

  std::vector<Vec3> points;
  for (const IntersectingPair& p : pairs) intersection_vertices(o.triangle(p.tri_a), o.triangle(p.tri_b), points);
  for (Index v : walk.inside) points.push_back(o.positions[static_cast<size_t>(v)]);
  // The overlapping faces of both sides are this object's; T = -n translates a face's
  // sheet back (the other sheet lies on its outward side).
  return finish_depth(pd, deepest.found ? deepest.nearest.distance : -1.0, points, {&o, &o}, {-1.0, -1.0});
}

/// The entry of a self-intersecting object: its contacts (see above), in the order of their
/// smallest triangle ids, reported as the first contact that is too_deep or undecided if any
/// (no number may hide a deeper or unknown overlap), else the contact of greatest depth (the
/// first of equally deep ones).
PenetrationDepth self_depth(const ObjectView& view, PdStatus surface,
                            std::vector<IntersectingPair>::const_iterator first,
                            std::vector<IntersectingPair>::const_iterator last) {
  const Object& o = *view.object;
  const Index object = first->object_a;
  if (surface != PdStatus::Ok) {
    PenetrationDepth pd;
    pd.objects = {object, object};
    for (auto it = first; it != last; ++it) {
      pd.overlapping_triangles[0].push_back(it->tri_a);
      pd.overlapping_triangles[0].push_back(it->tri_b);
    }
    auto& all = pd.overlapping_triangles[0];
    std::sort(all.begin(), all.end());
    all.erase(std::unique(all.begin(), all.end()), all.end());
    pd.status = surface;
    return pd;
  }
  // Contacts: pairs linked through shared triangles or triangles sharing a vertex.
  const size_t n = static_cast<size_t>(o.num_triangles());
  std::vector<char> hit(n, 0);
  for (auto it = first; it != last; ++it) hit[static_cast<size_t>(it->tri_a)] = hit[static_cast<size_t>(it->tri_b)] = 1;
  DisjointSets sets(n);
  const Adjacency& adj = adjacency(*o.topology);
  for (auto it = first; it != last; ++it) {
    sets.unite(it->tri_a, it->tri_b);
    for (Index t : {it->tri_a, it->tri_b})  // t's 1-ring (and t itself: a no-op)
      for (Index v : o.topology->faces[static_cast<size_t>(t)])
        for (Index u : adj.vertex_triangles(v))
          if (hit[static_cast<size_t>(u)]) sets.unite(t, u);
  }
  std::vector<std::pair<Index, size_t>> keyed;  // (contact root, position), in pair order
  for (auto it = first; it != last; ++it) keyed.emplace_back(sets.find(it->tri_a), static_cast<size_t>(it - first));
  std::stable_sort(keyed.begin(), keyed.end(),
                   [](const auto& a, const auto& b) { return a.first < b.first; });
  SelfContext ctx(view);
  ctx.mark_crossings(first, last);
  std::vector<int> stamp(n, -1);
  int next_stamp = 0;
  PenetrationDepth chosen;
  bool have = false;
  for (size_t k = 0; k < keyed.size();) {
    std::vector<IntersectingPair> contact;
    size_t e = k;
    for (; e < keyed.size() && keyed[e].first == keyed[k].first; ++e) contact.push_back(*(first + static_cast<std::ptrdiff_t>(keyed[e].second)));
    k = e;
    PenetrationDepth pd = self_contact_depth(ctx, object, contact, stamp, next_stamp);
    if (pd.status == PdStatus::TooDeep || pd.status == PdStatus::SelfIntersection) return pd;
    if (!have || (pd.status == PdStatus::Ok && (chosen.status != PdStatus::Ok || pd.depth > chosen.depth))) {
      chosen = std::move(pd);
      have = true;
    }
  }
  return chosen;
}

/// PD of one object pair, given its intersecting triangle pairs [first, last).
PenetrationDepth pair_depth(const std::vector<ObjectView>& views,
                            const std::vector<PdStatus>& surface,
                            std::vector<IntersectingPair>::const_iterator first,
                            std::vector<IntersectingPair>::const_iterator last) {
  PenetrationDepth pd;
  const Index ia = first->object_a, ib = first->object_b;
  pd.objects = {ia, ib};
  std::array<std::vector<Index>, 2> hit;  // intersecting triangles of each side
  for (auto it = first; it != last; ++it) {
    hit[0].push_back(it->tri_a);
    hit[1].push_back(it->tri_b);
  }
  for (auto& h : hit) {
    std::sort(h.begin(), h.end());
    h.erase(std::unique(h.begin(), h.end()), h.end());
  }
  if (ia == ib) return self_depth(views[static_cast<size_t>(ia)], surface[static_cast<size_t>(ia)], first, last);
  const ObjectView& va = views[static_cast<size_t>(ia)];
  const ObjectView& vb = views[static_cast<size_t>(ib)];
  pd.overlapping_triangles = hit;
  for (Index o : {ia, ib}) {
    const PdStatus s = surface[static_cast<size_t>(o)];
    if (s != PdStatus::Ok) {
      pd.status = s;
      return pd;
    }
  }
  const Walk wa = walk_inside(va, vb, hit[0]);
  const Walk wb = walk_inside(vb, va, hit[1]);
  pd.inside_vertices = {wa.inside, wb.inside};
  pd.overlapping_triangles = {overlapping_triangles(*va.object, hit[0], wa.inside),
                              overlapping_triangles(*vb.object, hit[1], wb.inside)};
  if (wa.swallowed || wb.swallowed) {
    pd.status = PdStatus::TooDeep;
    return pd;
  }
  // T: the inside vertex farthest from the other surface (exactly; ties: side 0 first, then
  // the smallest vertex id), and the translation of objects[0] that takes it out. A vertex's
  // search stops once it finds a point nearer than the deepest so far (by more than the
  // slack): it cannot be deeper then (max-min; deep overlaps of fine meshes went as n^1.5
  // without it).
  const double slack = pd_slack(std::max(va.scale, vb.scale));
  Deepest deepest;
  for (int side = 0; side < 2; ++side) {
    const ObjectView& own = side == 0 ? va : vb;
    const ObjectView& other = side == 0 ? vb : va;
    for (Index v : pd.inside_vertices[static_cast<size_t>(side)]) {
      const Vec3& p = own.object->positions[static_cast<size_t>(v)];
      const Nearest near = nearest_point(
          p, other, slack, [](Index) { return false; }, deepest.found ? deepest.nearest.distance : -1.0);
      if (deepest.deeper(p, near, *other.object, slack)) {
        deepest.take(p, near, *other.object);
        pd.deepest_object = side == 0 ? ia : ib;
        pd.deepest_vertex = v;
        pd.deepest_point = p;
        pd.nearest_point = near.point;
        pd.direction = side == 0 ? Vec3(near.point - p) : Vec3(p - near.point);
      }
    }
  }
  // Depth: the width along T of the overlap region's boundary vertices near the contact.
  std::vector<Vec3> points;
  for (auto it = first; it != last; ++it)
    intersection_vertices(va.object->triangle(it->tri_a), vb.object->triangle(it->tri_b), points);
  for (Index v : wa.inside) points.push_back(va.object->positions[static_cast<size_t>(v)]);
  for (Index v : wb.inside) points.push_back(vb.object->positions[static_cast<size_t>(v)]);
  // Face normals point out of B: +n for B's faces, -n for A's (outward normals).
  return finish_depth(pd, deepest.found ? deepest.nearest.distance : -1.0, points, {va.object, vb.object},
                      {-1.0, 1.0});
}

}  // namespace

int winding_number_brute_force(const Vec3& p, const Object& object, bool& on_surface) {
  on_surface = false;
  for (Index t = 0; t < object.num_triangles(); ++t)
    if (on_triangle(p, object.triangle(t))) {
      on_surface = true;
      return 0;
    }
  int w = 0;
  for (Index t = 0; t < object.num_triangles(); ++t) w += ray_crossing(p, object.triangle(t));
  return w;
}

PenetrationDepthOutput penetration_depth(const Frame& frame, const FrameBoxes& boxes,
                                         const std::vector<IntersectingPair>& intersecting,
                                         const PenetrationDepthOptions& opts) {
  Stopwatch sw;
  PenetrationDepthOutput out;
  const int threads = std::max(1, opts.threads);
  const size_t n = frame.objects.size();
  // Runs of one object pair in the sorted list.
  std::vector<std::pair<size_t, size_t>> runs;
  std::vector<char> involved(n, 0);
  for (size_t k = 0; k < intersecting.size();) {
    size_t e = k;
    while (e < intersecting.size() && intersecting[e].object_a == intersecting[k].object_a &&
           intersecting[e].object_b == intersecting[k].object_b)
      ++e;
    runs.emplace_back(k, e);
    involved[static_cast<size_t>(intersecting[k].object_a)] = 1;
    involved[static_cast<size_t>(intersecting[k].object_b)] = 1;
    k = e;
  }
  std::vector<PdStatus> surface(n, PdStatus::Ok);
  std::vector<ObjectView> views(n);
  parallel_for(n, threads, [&](size_t i) {
    if (!involved[i]) return;
    views[i] = {&frame.objects[i], &boxes.bvh(i), boxes.magnitudes[i]};
    surface[i] = surface_status(*frame.objects[i].topology);
  });
  out.pairs.resize(runs.size());
  parallel_for(runs.size(), threads, [&](size_t r) {
    out.pairs[r] = pair_depth(views, surface, intersecting.begin() + static_cast<std::ptrdiff_t>(runs[r].first),
                              intersecting.begin() + static_cast<std::ptrdiff_t>(runs[r].second));
  });
  out.ms = sw.elapsed_ms();
  return out;
}

}  // namespace vproxq
