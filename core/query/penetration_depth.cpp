#include "core/query/penetration_depth.hpp"

#include "core/broad_phase/triangle_bvh.hpp"
#include "core/geometry/point_triangle.hpp"
#include "core/geometry/predicates.hpp"
#include "core/geometry/triangle_intersection.hpp"
#include "core/mesh/adjacency.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"

#include <algorithm>
#include <cmath>
#include <deque>
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

/// The signed crossing of triangle t by the ray from p: +1/-1, 0 (missed), or sets on_surface.
int ray_crossing(const Vec3& p, const Triangle& t, bool& on_surface) {
  const int s = orient2d_projected(t[0], t[1], t[2], 0);
  if (s == 0) return 0;
  for (int k = 0; k < 3; ++k)
    if (orient_yz_perturbed(t[static_cast<size_t>(k)], t[static_cast<size_t>((k + 1) % 3)], p) != s) return 0;
  const int above = orient3d(t[0], t[1], t[2], p);  // sign of n.(p - a) = n.x (p.x - plane.x)
  if (above == 0) {
    on_surface = true;  // p is in the plane and inside the (closed) projection: on t
    return 0;
  }
  return above == -s ? s : 0;  // ahead of p iff p.x < plane.x iff sign(n.(p-a)) == -sign(n.x)
}

/// Winding number of `o` around p through its BVH: only faces whose box meets the ray.
int winding_number(const Vec3& p, const Object& o, const TriangleBvh& bvh, bool& on_surface) {
  AABB ray;
  ray.lo = p;
  ray.hi = Vec3(kInfinity, p.y(), p.z());
  int w = 0;
  on_surface = false;
  bvh.query(ray, [] { return 0.0; }, [&](Index t, double) {
    if (on_surface) return;
    w += ray_crossing(p, o.triangle(t), on_surface);
  });
  return on_surface ? 0 : w;
}

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

struct ObjectView {
  const Object* object;
  const TriangleBvh* bvh;
};

struct Walk {
  std::vector<Index> inside;  ///< ascending
  bool swallowed = false;     ///< some connected set of inside vertices has no outside neighbour
};

/// Vertices of `a` inside `b`, connected to the seeds through inside vertices.
Walk walk_inside(const ObjectView& a, const ObjectView& b, const std::vector<Index>& seed_triangles) {
  const Object& oa = *a.object;
  const Adjacency& adj = adjacency(*oa.topology);
  enum : std::int8_t { kUnknown = 0, kInside = 1, kOutside = 2 };
  std::vector<std::int8_t> state(static_cast<size_t>(oa.num_vertices()), kUnknown);
  auto classify = [&](Index v) {
    bool on = false;
    const int w = winding_number(oa.positions[static_cast<size_t>(v)], *b.object, *b.bvh, on);
    // On the other surface counts as outside: such a vertex is a vertex of an intersection
    // segment, which the depth takes into account anyway.
    state[static_cast<size_t>(v)] = (!on && w != 0) ? kInside : kOutside;
  };
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
    queue.push_back(s);
    expanded[static_cast<size_t>(s)] = 1;
    while (!queue.empty()) {
      const Index v = queue.front();
      queue.pop_front();
      walk.inside.push_back(v);
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
  }
  std::sort(walk.inside.begin(), walk.inside.end());
  return walk;
}

/// Nearest point of `o`'s surface to p (ties: the smallest triangle id).
std::pair<double, Vec3> nearest_point(const Vec3& p, const ObjectView& o) {
  double best_sq = kInfinity;
  Index best_t = kNoIndex;
  Vec3 best_q = p;
  AABB box;
  box.lo = box.hi = p;
  o.bvh->query(box, [&] { return std::sqrt(best_sq); }, [&](Index t, double d2) {
    if (d2 > best_sq) return;
    const PointTriangleResult r = point_triangle_distance(p, o.object->triangle(t));
    if (r.squared_distance < best_sq || (r.squared_distance == best_sq && t < best_t)) {
      best_sq = r.squared_distance;
      best_t = t;
      best_q = r.closest;
    }
  });
  return {std::sqrt(best_sq), best_q};
}

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
  if (ia == ib) {
    // Both sheets belong to one object: which side of the other sheet is "inside" needs a
    // winding number relative to that sheet alone; not computed in this version.
    std::vector<Index> all = hit[0];
    all.insert(all.end(), hit[1].begin(), hit[1].end());
    std::sort(all.begin(), all.end());
    all.erase(std::unique(all.begin(), all.end()), all.end());
    pd.status = PdStatus::SelfIntersection;
    pd.overlapping_triangles = {all, all};
    return pd;
  }
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
  // T: the inside vertex farthest from the other surface (ties: side 0 first, then the
  // smallest vertex id), and the translation of objects[0] that takes it out.
  double best = -1;
  for (int side = 0; side < 2; ++side) {
    const ObjectView& own = side == 0 ? va : vb;
    const ObjectView& other = side == 0 ? vb : va;
    for (Index v : pd.inside_vertices[static_cast<size_t>(side)]) {
      const Vec3& p = own.object->positions[static_cast<size_t>(v)];
      const auto [d, q] = nearest_point(p, other);
      if (d > best) {
        best = d;
        pd.deepest_object = side == 0 ? ia : ib;
        pd.deepest_vertex = v;
        pd.deepest_point = p;
        pd.nearest_point = q;
        pd.direction = side == 0 ? Vec3(q - p) : Vec3(p - q);
      }
    }
  }
  // Depth: the width along T of the overlap region's boundary vertices near the contact.
  std::vector<Vec3> points;
  for (auto it = first; it != last; ++it)
    intersection_vertices(va.object->triangle(it->tri_a), vb.object->triangle(it->tri_b), points);
  for (Index v : wa.inside) points.push_back(va.object->positions[static_cast<size_t>(v)]);
  for (Index v : wb.inside) points.push_back(vb.object->positions[static_cast<size_t>(v)]);
  if (best > 0) {
    pd.direction /= pd.direction.norm();
    pd.depth = width(points, pd.direction);
    pd.status = PdStatus::Ok;
    return pd;
  }
  // No vertex lies strictly inside the other object (a shallow overlap, or faces lying on
  // each other, as for two boxes sliding into each other face to face): the paper's distance
  // pairs are all 0. T is then the overlapping face normal along which the overlap is
  // narrowest (for a convex overlap, a facet normal is a candidate minimal translation
  // direction), pointing out of B: +n for B's faces, -n for A's (outward normals).
  pd.deepest_object = pd.deepest_vertex = kNoIndex;
  pd.deepest_point = pd.nearest_point = Vec3::Zero();
  double narrowest = kInfinity;
  for (int side = 0; side < 2; ++side) {
    const ObjectView& own = side == 0 ? va : vb;
    for (Index t : pd.overlapping_triangles[static_cast<size_t>(side)]) {
      const Triangle tri = own.object->triangle(t);
      Vec3 n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
      const double len = n.norm();
      if (!(len > 0)) continue;
      n /= len;
      const double w = width(points, n);
      if (w < narrowest) {
        narrowest = w;
        pd.direction = side == 0 ? Vec3(-n) : n;
      }
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

}  // namespace

int winding_number_brute_force(const Vec3& p, const Object& object, bool& on_surface) {
  on_surface = false;
  int w = 0;
  for (Index t = 0; t < object.num_triangles(); ++t) {
    w += ray_crossing(p, object.triangle(t), on_surface);
    if (on_surface) return 0;
  }
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
    if (intersecting[k].object_a != intersecting[k].object_b) {
      involved[static_cast<size_t>(intersecting[k].object_a)] = 1;
      involved[static_cast<size_t>(intersecting[k].object_b)] = 1;
    }
    k = e;
  }
  std::vector<TriangleBvh> bvhs(n);
  std::vector<PdStatus> surface(n, PdStatus::Ok);
  parallel_for(n, threads, [&](size_t i) {
    if (!involved[i]) return;
    bvhs[i].build(boxes.triangles[i]);
    surface[i] = surface_status(*frame.objects[i].topology);
  });
  std::vector<ObjectView> views(n);
  for (size_t i = 0; i < n; ++i) views[i] = {&frame.objects[i], &bvhs[i]};
  out.pairs.resize(runs.size());
  parallel_for(runs.size(), threads, [&](size_t r) {
    out.pairs[r] = pair_depth(views, surface, intersecting.begin() + static_cast<std::ptrdiff_t>(runs[r].first),
                              intersecting.begin() + static_cast<std::ptrdiff_t>(runs[r].second));
  });
  out.ms = sw.elapsed_ms();
  return out;
}

}  // namespace vproxq
