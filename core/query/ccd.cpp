#include "core/query/ccd.hpp"

#include "core/broad_phase/object_broad_phase.hpp"
#include "core/broad_phase/triangle_bvh.hpp"
#include "core/geometry/ccd.hpp"
#include "core/geometry/diagonals.hpp"
#include "core/geometry/separation_bound.hpp"
#include "core/mesh/adjacency.hpp"
#include "core/parallel.hpp"
#include "core/timer.hpp"
#include "core/voronoi/ccd_stage2.hpp"

#include <Eigen/Geometry>
#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <set>
#include <tuple>
#include <unordered_map>

namespace vproxq {
namespace {

bool in_face(Index v, const Face& f) { return f[0] == v || f[1] == v || f[2] == v; }

/// Whether entry k of a triangle's corners or edge ids repeats an earlier one (a face with a
/// repeated vertex lists that vertex twice and its one real edge twice): each is tested once.
bool repeats_earlier(const std::array<Index, 3>& a, size_t k) {
  return (k >= 1 && a[k] == a[0]) || (k == 2 && a[2] == a[1]);
}

bool share_endpoint(const std::array<Index, 2>& a, const std::array<Index, 2>& b) {
  return a[0] == b[0] || a[0] == b[1] || a[1] == b[0] || a[1] == b[1];
}

// Deduplication by ownership: a vertex is owned by one of its incident triangles, an edge by
// one of its incident triangles (any rule works; the pipeline prefers the triangle whose
// busiest corner has the fewest incident triangles, then the smaller id; the brute force takes
// the smallest id). A candidate triangle pair (f, g) tests vertex v of f against face g only if
// f owns v, and edge e of f against edge e' of g only if f owns e and g owns e'. So each
// primitive pair is tested from exactly one triangle pair. No pair that can be reported is
// lost: if the kernel can report (v, g), v's swept path comes within the margin of g's swept
// prism, and v's path lies in the swept prism (and box) of every triangle using v — in
// particular its owner's — so the culling keeps (owner(v), g); likewise for edges.
//   The preference keeps the rim vertices and rim edges of a fan (the cap of a cylinder with
// thousands of segments) with the triangles beside it, so the fan's triangles own only
// primitives that contain its hub; see pivots() for what that buys.
struct Ownership {
  std::vector<Index> vertex;  ///< owner triangle per vertex (kNoIndex: used by no face)
  std::vector<Index> edge;    ///< owner triangle per edge id
};

/// `prefer_quiet`: the pipeline's rule above; else the smallest id.
Ownership ownership(const Topology& topo, bool prefer_quiet = false) {
  const Adjacency& adj = adjacency(topo);
  std::vector<std::size_t> busiest;
  if (prefer_quiet) {
    busiest.resize(static_cast<size_t>(topo.num_triangles()));
    for (size_t t = 0; t < busiest.size(); ++t)
      for (const Index v : topo.faces[t]) busiest[t] = std::max(busiest[t], adj.vertex_triangles(v).size());
  }
  auto pick = [&](IndexSpan tris) {
    Index best = tris[0];
    if (prefer_quiet)
      for (const Index t : tris) {
        const size_t a = busiest[static_cast<size_t>(t)], b = busiest[static_cast<size_t>(best)];
        if (a < b || (a == b && t < best)) best = t;
      }
    return best;
  };
  Ownership o;
  o.vertex.assign(static_cast<size_t>(topo.num_vertices), kNoIndex);
  for (Index v = 0; v < topo.num_vertices; ++v) {
    const IndexSpan tris = adj.vertex_triangles(v);
    if (!tris.empty()) o.vertex[static_cast<size_t>(v)] = pick(tris);
  }
  o.edge.resize(adj.edges().size());
  for (size_t e = 0; e < adj.edges().size(); ++e) o.edge[e] = pick(adj.edge_triangles(static_cast<Index>(e)));
  return o;
}

/// Per triangle, its pivots: its vertices that every primitive it owns contains (all three if
/// it owns none), ascending, kNoIndex after the last. Two triangles of one object with a
/// common pivot c (c is then a vertex of both) have no primitive pair to test: an owned
/// vertex is c itself, a corner of the other face; two owned edges both end at c. So a self
/// search from f skips a pair, and a BVH subtree, whose triangles all have a pivot of f as a
/// pivot (TriangleBvh::node_common_vertices() of the pivots): the triangles of a fan around
/// one hub all overlap there, and without this each pair of them was a candidate (a cylinder
/// of 8,000 segments: 64 M triangle pairs per step).
std::vector<Face> pivots(const Topology& topo, const Ownership& own) {
  const Adjacency& adj = adjacency(topo);
  std::vector<Face> out(static_cast<size_t>(topo.num_triangles()));
  for (Index t = 0; t < topo.num_triangles(); ++t) {
    const Face& f = topo.faces[static_cast<size_t>(t)];
    Face p{kNoIndex, kNoIndex, kNoIndex};
    int n = 0;
    for (size_t k = 0; k < 3; ++k) {
      const Index c = f[k];
      if (repeats_earlier(f, k)) continue;
      bool all = true;
      for (size_t m = 0; m < 3 && all; ++m)
        if (own.vertex[static_cast<size_t>(f[m])] == t && f[m] != c) all = false;
      for (const Index e : adj.triangle_edges(t)) {
        if (!all) break;
        if (e == kNoIndex || own.edge[static_cast<size_t>(e)] != t) continue;
        const auto& ends = adj.edges()[static_cast<size_t>(e)];
        if (ends[0] != c && ends[1] != c) all = false;
      }
      if (all) p[static_cast<size_t>(n++)] = c;
    }
    for (int a = 1; a < n; ++a)  // ascending
      for (int b = a; b > 0 && p[static_cast<size_t>(b)] < p[static_cast<size_t>(b - 1)]; --b)
        std::swap(p[static_cast<size_t>(b)], p[static_cast<size_t>(b - 1)]);
    out[static_cast<size_t>(t)] = p;
  }
  return out;
}

/// A triangle's corners at the start and at the end of the step, with the axes it offers to
/// swept_apart(): its normal at the start and the sum of its corners at the start; and its
/// normal at the end (for primitives_apart()).
struct SweptTriangle {
  std::array<Vec3, 3> start, end;
  Vec3 normal, corner_sum, normal_end;
  Vec3 motion;         ///< the sum of its corners' displacements over the step (3x the centroid's)
  double size = 0;     ///< the diagonal of its box at the start
};

std::vector<SweptTriangle> swept_triangles(const Object& from, const Object& to) {
  std::vector<SweptTriangle> out(static_cast<size_t>(from.num_triangles()));
  for (size_t t = 0; t < out.size(); ++t) {
    const Face& f = from.topology->faces[t];
    SweptTriangle& s = out[t];
    for (size_t k = 0; k < 3; ++k) {
      s.start[k] = from.positions[static_cast<size_t>(f[k])];
      s.end[k] = to.positions[static_cast<size_t>(f[k])];
    }
    s.normal = (s.start[1] - s.start[0]).cross(s.start[2] - s.start[0]);
    s.corner_sum = s.start[0] + s.start[1] + s.start[2];
    s.normal_end = (s.end[1] - s.end[0]).cross(s.end[2] - s.end[0]);
    s.motion = (s.end[0] + s.end[1] + s.end[2]) - s.corner_sum;
    const Vec3 lo = s.start[0].cwiseMin(s.start[1]).cwiseMin(s.start[2]);
    const Vec3 hi = s.start[0].cwiseMax(s.start[1]).cwiseMax(s.start[2]);
    s.size = (hi - lo).norm();
  }
  return out;
}

/// Whether the points a (each moving linearly from a_start to a_end) and the points b stay
/// more than `gap` apart along the axis w for the whole step, hence so do their convex hulls:
/// at time t, (smallest projection of b) - (largest of a) is a minimum of linear functions of t
/// minus a maximum of linear functions, so it is concave and at least its smaller end value
/// (the same with a and b swapped). The gap is compared with |w| itself, so w need not be a
/// unit vector; the dot products are off by a few 2^-53 |w| M (M: largest coordinate), far
/// below the rounding slack that `gap` includes.
template <std::size_t NA, std::size_t NB>
bool points_apart_along(const std::array<Vec3, NA>& a_start, const std::array<Vec3, NA>& a_end,
                        const std::array<Vec3, NB>& b_start, const std::array<Vec3, NB>& b_end,
                        const Vec3& w, double gap) {
  auto gaps = [&w](const std::array<Vec3, NA>& a, const std::array<Vec3, NB>& b) {
    double a_lo = kInfinity, a_hi = -kInfinity, b_lo = kInfinity, b_hi = -kInfinity;
    for (const Vec3& x : a) {
      a_lo = std::min(a_lo, w.dot(x));
      a_hi = std::max(a_hi, w.dot(x));
    }
    for (const Vec3& x : b) {
      b_lo = std::min(b_lo, w.dot(x));
      b_hi = std::max(b_hi, w.dot(x));
    }
    return ProjectionGaps{b_lo - a_hi, a_lo - b_hi};
  };
  const ProjectionGaps g0 = gaps(a_start, b_start), g1 = gaps(a_end, b_end);
  const double d = std::max(std::min(g0.b_above_a, g1.b_above_a), std::min(g0.a_above_b, g1.a_above_b));
  return d > 0 && d * d > gap * gap * w.squaredNorm();
}

/// Two axes perpendicular to r (the coordinate axis most nearly perpendicular to r, crossed
/// with r, and r crossed with that).
std::array<Vec3, 2> perpendicular_axes(const Vec3& r) {
  int k = 0;
  for (int c = 1; c < 3; ++c)
    if (std::abs(r[c]) < std::abs(r[k])) k = c;
  const Vec3 w1 = r.cross(Vec3::Unit(k));
  return {w1, r.cross(w1)};
}

/// Whether triangles a and b stay more than `gap` apart for the whole step, shown by
/// points_apart_along() on both normals at the start and the line through the centroids at
/// the start (any axis is valid); x, y and z are the same test on the triangles' boxes at both
/// ends (apart_at_both_ends, done first, being cheaper).
///
/// When the two move relative to each other by more than their sizes (a fast object crossing
/// a fine mesh, sideways), the triangle's path sweeps over many others, and each is ahead on
/// every one of those axes at one end of the step and behind at the other. Two axes
/// perpendicular to the relative motion r of the centroids then see the pair as nearly static:
/// a rigid translation by r leaves every projection onto them unchanged, so only the triangles
/// whose projections overlap — those along the path — remain.
bool swept_apart(const SweptTriangle& a, const SweptTriangle& b, double gap) {
  if (points_apart_along(a.start, a.end, b.start, b.end, a.normal, gap) ||
      points_apart_along(a.start, a.end, b.start, b.end, b.normal, gap) ||
      points_apart_along(a.start, a.end, b.start, b.end, b.corner_sum - a.corner_sum, gap))
    return true;
  const Vec3 r = b.motion - a.motion;  // 3x the relative motion of the centroids
  const double sizes = a.size + b.size;
  if (!(r.squaredNorm() > 9 * sizes * sizes)) return false;  // moved less than their sizes
  const auto w = perpendicular_axes(r);
  return points_apart_along(a.start, a.end, b.start, b.end, w[0], gap) ||
         points_apart_along(a.start, a.end, b.start, b.end, w[1], gap);
}

/// A vertex and a face's corners (NA = 1, NB = 3) or two edges' end points (2, 2), at the
/// start and at the end of the step.
template <std::size_t NA, std::size_t NB>
struct SweptPrimitives {
  std::array<Vec3, NA> a_start, a_end;
  std::array<Vec3, NB> b_start, b_end;
};

/// Whether two primitives stay more than `gap` apart for the whole step, shown along x, y, z
/// or one of `axes` (points_apart_along()), with the primitives' own points (every point of
/// a primitive is a convex combination of them, so its projection lies between theirs). A
/// pair this rules out is one the elementary test cannot report (gap: see apart_gap below).
/// Along a coordinate axis the projections are the coordinates themselves (exact).
template <std::size_t NA, std::size_t NB>
bool primitives_apart(const SweptPrimitives<NA, NB>& p, std::initializer_list<Vec3> axes, double gap) {
  for (int k = 0; k < 3; ++k)
    if (points_apart_along(p.a_start, p.a_end, p.b_start, p.b_end, Vec3::Unit(k), gap)) return true;
  for (const Vec3& w : axes)
    if (points_apart_along(p.a_start, p.a_end, p.b_start, p.b_end, w, gap)) return true;
  return false;
}

/// primitives_apart()'s test along the given axes only, built when needed: `axis(k)` for k in
/// [0, n). The in-plane axes below come after the others: they cost a cross product each, and
/// as products of three coordinate differences they are scaled by a power of two to a largest
/// component in [1, 2) (exact, so a scene scaled by a power of two is culled alike; unscaled,
/// the squared gaps of a scene at 2^-150 underflowed).
template <std::size_t NA, std::size_t NB, typename Axis>
bool apart_along_any(const SweptPrimitives<NA, NB>& p, int n, const Axis& axis, double gap) {
  for (int k = 0; k < n; ++k) {
    Vec3 w = axis(k);
    const double m = w.cwiseAbs().maxCoeff();
    if (!(m > 0) || !std::isfinite(m)) continue;
    w *= std::ldexp(1.0, -std::ilogb(m));
    if (points_apart_along(p.a_start, p.a_end, p.b_start, p.b_end, w, gap)) return true;
  }
  return false;
}

/// Whether every primitive pair of two triangles of one object that share exactly one vertex
/// c stays more than `gap` apart for the whole step: f's other corners a, b and g's other
/// corners d, e lie on opposite sides of c along one axis w, by more than `gap` at both ends.
/// Every primitive pair of the two that the pipeline can test leaves out c on one side (a pair
/// with c on both sides is a vertex of its own face or two edges with a common endpoint, never
/// tested): either f's part lies in {a, b} and g's in {c, d, e}, or f's in {c, a, b} and g's in
/// {d, e}. points_apart_along() of those point sets along w bounds the gap of each such pair
/// (a subset's projections lie within its set's), so when both are apart, so is every pair
/// (the same argument as primitives_apart(), with one axis for all of them).
/// w: from c, the directions to a and b (unit vectors at the start) less those to d and e; in
/// a flat patch around c, where f and g lie in sectors that a line through c separates (a
/// triangle and the ones beyond its edge neighbours), it points from g's sector to f's.
/// Unit vectors scale exactly with a power-of-two scaling of the scene, so the culling does.
bool apart_around_vertex(const std::array<Vec3, 2>& f_start, const std::array<Vec3, 2>& f_end,
                         const std::array<Vec3, 2>& g_start, const std::array<Vec3, 2>& g_end,
                         const Vec3& c_start, const Vec3& c_end, double gap) {
  Vec3 w = Vec3::Zero();
  for (const Vec3& p : f_start) w += (p - c_start).normalized();
  for (const Vec3& p : g_start) w -= (p - c_start).normalized();
  if (!(w.squaredNorm() > 0) || !w.allFinite()) return false;
  const std::array<Vec3, 3> f_with_c_start{c_start, f_start[0], f_start[1]}, f_with_c_end{c_end, f_end[0], f_end[1]};
  const std::array<Vec3, 3> g_with_c_start{c_start, g_start[0], g_start[1]}, g_with_c_end{c_end, g_end[0], g_end[1]};
  return points_apart_along(f_start, f_end, g_with_c_start, g_with_c_end, w, gap) &&
         points_apart_along(f_with_c_start, f_with_c_end, g_start, g_end, w, gap);
}

/// The largest |coordinate| of a box.
double box_magnitude(const AABB& b) { return std::max(b.lo.cwiseAbs().maxCoeff(), b.hi.cwiseAbs().maxCoeff()); }

/// A point set's share of the culling margin (ccd_tolerance_share() plus its rounding slack):
/// two sets whose boxes come within their pair's margin have shares that add up to it.
double margin_share(const AABB& raw) {
  const double m = box_magnitude(raw);
  return ccd_tolerance_share((raw.hi - raw.lo).maxCoeff(), m) + rounding_slack(m) * ccd_share_factor();
}

/// apart_at_both_ends() along the diagonals (Diagonals): the points of a and b (a0, b0 at the
/// start of the step, a1, b1 at its end) stay more than `gap` apart along some diagonal w, the
/// same one of the two ahead at both ends (so at every time between: points_apart_along()).
/// The projections are exact but for the two roundings of the sums (a few 2^-53 M, M the
/// largest coordinate), far below the rounding slack that `gap` includes, and |w|^2 = 3.
bool diagonals_apart(const Diagonals& a0, const Diagonals& a1, const Diagonals& b0, const Diagonals& b1, double gap) {
  const double limit = 3 * gap * gap;
  for (size_t d = 0; d < 4; ++d) {
    const double ahead = std::max(std::min(b0.lo[d] - a0.hi[d], b1.lo[d] - a1.hi[d]),
                                  std::min(a0.lo[d] - b0.hi[d], a1.lo[d] - b1.hi[d]));
    if (ahead > 0 && ahead * ahead > limit) return true;
  }
  return false;
}

/// Per triangle and per BVH node: the boxes of its points at the start and at the end of the
/// step, and its share of the culling margin (margin_share() of both boxes together: the
/// triangles' from CcdSweep::shares). A pair
/// of a triangle and a triangle or subtree uses the sum of their shares as its margin: if the
/// kernel can report one of its queries, their swept boxes come within that query's margin on
/// every axis, and there the shares add up to at least the margin (ccd_tolerance_share()).
/// The same for the projections onto the diagonals (Diagonals).
struct EndBoxes {
  std::vector<AABB> start, end, node_start, node_end;
  std::vector<double> share, node_share;
  std::vector<Diagonals> diag_start, diag_end, node_diag_start, node_diag_end;

  static EndBoxes of(const std::vector<SweptTriangle>& tris, const TriangleBvh& bvh, const std::vector<double>& shares) {
    EndBoxes e;
    e.start.resize(tris.size());
    e.end.resize(tris.size());
    e.share = shares;
    e.diag_start.resize(tris.size());
    e.diag_end.resize(tris.size());
    for (size_t t = 0; t < tris.size(); ++t)
      for (size_t k = 0; k < 3; ++k) {
        e.start[t].extend(tris[t].start[k]);
        e.end[t].extend(tris[t].end[k]);
        e.diag_start[t].extend(tris[t].start[k]);
        e.diag_end[t].extend(tris[t].end[k]);
      }
    e.node_start = bvh.node_unions(e.start);
    e.node_end = bvh.node_unions(e.end);
    e.node_diag_start = node_diagonals(bvh, e.diag_start);
    e.node_diag_end = node_diagonals(bvh, e.diag_end);
    e.node_share.resize(e.node_start.size());
    for (size_t n = 0; n < e.node_start.size(); ++n) {
      AABB both = e.node_start[n];
      both.extend(e.node_end[n]);
      e.node_share[n] = both.empty() ? 0.0 : margin_share(both);
    }
    return e;
  }
};

/// Whether the points in boxes a and b (a_start, b_start at the start of the step, a_end,
/// b_end at its end) stay more than `gap` apart for the whole step: along some axis, the same
/// one of the two is ahead by more than `gap` at both ends. A point moving linearly has, at
/// time t, the coordinate (1 - t) x(0) + t x(1), so the gap at t is at least the same blend of
/// the two end gaps (the same argument as swept_apart(), with boxes).
bool apart_at_both_ends(const AABB& a_start, const AABB& a_end, const AABB& b_start,
                        const AABB& b_end, double gap) {
  for (int k = 0; k < 3; ++k) {
    if (b_start.lo[k] - a_start.hi[k] > gap && b_end.lo[k] - a_end.hi[k] > gap) return true;
    if (a_start.lo[k] - b_start.hi[k] > gap && a_end.lo[k] - b_end.hi[k] > gap) return true;
  }
  return false;
}

/// apart_at_both_ends() along any axis w: a box's projection onto w is its center's ± its half
/// extents' projection onto |w| (rounding: as in points_apart_along()).
bool boxes_apart_along(const AABB& a_start, const AABB& a_end, const AABB& b_start, const AABB& b_end,
                       const Vec3& w, double gap) {
  const Vec3 aw = w.cwiseAbs();
  auto range = [&](const AABB& b) {
    const double c = 0.5 * w.dot(b.lo + b.hi), h = 0.5 * aw.dot(b.hi - b.lo);
    return std::pair<double, double>{c - h, c + h};
  };
  const auto [a0lo, a0hi] = range(a_start);
  const auto [a1lo, a1hi] = range(a_end);
  const auto [b0lo, b0hi] = range(b_start);
  const auto [b1lo, b1hi] = range(b_end);
  const double d = std::max(std::min(b0lo - a0hi, b1lo - a1hi), std::min(a0lo - b0hi, a1lo - b1hi));
  return d > 0 && d * d > gap * gap * w.squaredNorm();
}

/// Results and counters of one unit of work.
struct Hits {
  std::vector<CcdVertexFace> vf;
  std::vector<CcdEdgeEdge> ee;
  CcdCounters counters;
};

/// The elementary tests, with the argument order shared by the pipeline and the brute force
/// (so both compute bit-identical TOIs).
class Tester {
 public:
  Tester(const Frame& from, const Frame& to) : from_(from), to_(to) {}

  void vertex_face(Index ov, Index v, Index of, Index f, Hits& out) const {
    const Object& a0 = from_.objects[static_cast<size_t>(ov)];
    const Object& a1 = to_.objects[static_cast<size_t>(ov)];
    const Object& b0 = from_.objects[static_cast<size_t>(of)];
    const Object& b1 = to_.objects[static_cast<size_t>(of)];
    const Face& face = b0.topology->faces[static_cast<size_t>(f)];
    const std::array<Vec3, 4> s{a0.positions[static_cast<size_t>(v)], b0.positions[static_cast<size_t>(face[0])],
                                b0.positions[static_cast<size_t>(face[1])], b0.positions[static_cast<size_t>(face[2])]};
    const std::array<Vec3, 4> e{a1.positions[static_cast<size_t>(v)], b1.positions[static_cast<size_t>(face[0])],
                                b1.positions[static_cast<size_t>(face[1])], b1.positions[static_cast<size_t>(face[2])]};
    ++out.counters.vf_tests;
    const CcdResult r = vertex_face_ccd(s, e);
    out.counters.limit_hits += r.hit_limit;
    if (r.collides) out.vf.push_back({ov, v, of, f, r.toi});
  }

  /// (oa, ea) must be the smaller of the two (object, edge id).
  void edge_edge(Index oa, const std::array<Index, 2>& ea, Index ob, const std::array<Index, 2>& eb,
                 Hits& out) const {
    const Object& a0 = from_.objects[static_cast<size_t>(oa)];
    const Object& a1 = to_.objects[static_cast<size_t>(oa)];
    const Object& b0 = from_.objects[static_cast<size_t>(ob)];
    const Object& b1 = to_.objects[static_cast<size_t>(ob)];
    const std::array<Vec3, 4> s{a0.positions[static_cast<size_t>(ea[0])], a0.positions[static_cast<size_t>(ea[1])],
                                b0.positions[static_cast<size_t>(eb[0])], b0.positions[static_cast<size_t>(eb[1])]};
    const std::array<Vec3, 4> e{a1.positions[static_cast<size_t>(ea[0])], a1.positions[static_cast<size_t>(ea[1])],
                                b1.positions[static_cast<size_t>(eb[0])], b1.positions[static_cast<size_t>(eb[1])]};
    ++out.counters.ee_tests;
    const CcdResult r = edge_edge_ccd(s, e);
    out.counters.limit_hits += r.hit_limit;
    if (r.collides) out.ee.push_back({oa, ea, ob, eb, r.toi});
  }

 private:
  const Frame& from_;
  const Frame& to_;
};

AABB swept_box(const Object& a, const Object& b, std::initializer_list<Index> vertices) {
  AABB box;
  for (Index v : vertices) {
    box.extend(a.positions[static_cast<size_t>(v)]);
    box.extend(b.positions[static_cast<size_t>(v)]);
  }
  return box;
}

void add(CcdCounters& a, const CcdCounters& b) {
  a.object_pairs += b.object_pairs;
  a.triangle_pairs += b.triangle_pairs;
  a.vf_tests += b.vf_tests;
  a.ee_tests += b.ee_tests;
  a.limit_hits += b.limit_hits;
  a.culled_triangles += b.culled_triangles;
  a.separated_pairs += b.separated_pairs;
  a.unshared_pairs += b.unshared_pairs;
  a.separated_primitives += b.separated_primitives;
  a.voxelized_triangles += b.voxelized_triangles;
}

/// Sorts the hits canonically and summarises them per object pair.
void finish(std::vector<Hits>& parts, CcdStepResult& out) {
  for (Hits& h : parts) {
    out.vf.insert(out.vf.end(), h.vf.begin(), h.vf.end());
    out.ee.insert(out.ee.end(), h.ee.begin(), h.ee.end());
    add(out.counters, h.counters);
  }
  std::sort(out.vf.begin(), out.vf.end(), [](const CcdVertexFace& a, const CcdVertexFace& b) {
    return std::tie(a.object_v, a.vertex, a.object_f, a.face) <
           std::tie(b.object_v, b.vertex, b.object_f, b.face);
  });
  std::sort(out.ee.begin(), out.ee.end(), [](const CcdEdgeEdge& a, const CcdEdgeEdge& b) {
    return std::tie(a.object_a, a.edge_a, a.object_b, a.edge_b) <
           std::tie(b.object_a, b.edge_a, b.object_b, b.edge_b);
  });
  std::map<std::pair<Index, Index>, CcdObjectPair> pairs;
  auto note = [&](Index a, Index b, double toi) {
    const auto key = std::minmax(a, b);
    CcdObjectPair& p = pairs[{key.first, key.second}];
    if (p.primitive_pairs == 0 || toi < p.toi) p.toi = toi;
    p.objects = {key.first, key.second};
    ++p.primitive_pairs;
  };
  for (const auto& h : out.vf) note(h.object_v, h.object_f, h.toi);
  for (const auto& h : out.ee) note(h.object_a, h.object_b, h.toi);
  for (const auto& kv : pairs) out.pairs.push_back(kv.second);
}

constexpr Index kChunk = 256;  ///< triangles per unit of parallel work

/// Why a piece of a "components" object can lack a counterpart, for the skip reasons.
constexpr const char* kPieceRule =
    "pieces are matched by their vertices' indices in their mesh: this one split, merged with "
    "another, or vertices before it were added or removed";

/// Whether o is a connected component of a mesh ("objects": "components").
bool is_component(const Object& o) { return o.topology && !o.topology->origin.empty(); }

/// Orders components by what identifies them across frames: static or not, mesh, vertices.
struct ComponentLess {
  bool operator()(const Object* a, const Object* b) const {
    if (a->is_static != b->is_static) return a->is_static < b->is_static;
    return a->topology->origin < b->topology->origin;
  }
};

bool same_component(const Object& a, const Object& b) {
  return a.is_static == b.is_static && a.topology->origin == b.topology->origin;
}

/// Frames of components: each one's counterpart holds the same vertices of the same mesh.
/// Nullopt when they are in order already, or when one is listed twice in a frame (two meshes
/// of one name): then by position, where ccd_participants() checks the origins.
std::optional<Frame> counterparts_by_origin(const Frame& from, const Frame& to) {
  std::map<const Object*, size_t, ComponentLess> where;
  for (size_t k = 0; k < to.objects.size(); ++k)
    if (!where.emplace(&to.objects[k], k).second) return std::nullopt;
  std::set<const Object*, ComponentLess> seen;
  bool in_order = from.objects.size() == to.objects.size();
  for (size_t i = 0; i < from.objects.size(); ++i) {
    if (!seen.insert(&from.objects[i]).second) return std::nullopt;
    const auto it = where.find(&from.objects[i]);
    in_order = in_order && it != where.end() && it->second == i;
  }
  if (in_order) return std::nullopt;
  Frame aligned;
  aligned.index = to.index;
  aligned.files = to.files;
  aligned.objects.resize(from.objects.size());
  for (size_t i = 0; i < from.objects.size(); ++i) {
    const auto it = where.find(&from.objects[i]);
    if (it != where.end()) {
      aligned.objects[i] = to.objects[it->second];
    } else {
      aligned.objects[i].name = from.objects[i].name;  // no topology: no counterpart
    }
  }
  return aligned;
}

std::optional<Frame> counterparts_by_name(const Frame& from, const Frame& to) {
  bool same_order = from.objects.size() == to.objects.size();
  for (size_t i = 0; same_order && i < from.objects.size(); ++i)
    same_order = from.objects[i].name == to.objects[i].name;
  if (same_order) return std::nullopt;
  std::unordered_map<std::string, size_t> where;
  for (size_t k = 0; k < to.objects.size(); ++k)
    if (!where.emplace(to.objects[k].name, k).second) return std::nullopt;  // a name twice
  std::unordered_map<std::string, size_t> seen;
  bool moved = false;  // some object's name is found at another position
  for (size_t i = 0; i < from.objects.size(); ++i) {
    if (!seen.emplace(from.objects[i].name, i).second) return std::nullopt;
    const auto it = where.find(from.objects[i].name);
    moved = moved || (it != where.end() && it->second != i);
  }
  // Names that match nowhere else (taken from each frame's file name, say) say nothing.
  if (!moved) return std::nullopt;
  Frame aligned;
  aligned.index = to.index;
  aligned.files = to.files;
  aligned.objects.resize(from.objects.size());
  for (size_t i = 0; i < from.objects.size(); ++i) {
    const auto it = where.find(from.objects[i].name);
    if (it != where.end()) {
      aligned.objects[i] = to.objects[it->second];
    } else {
      aligned.objects[i].name = from.objects[i].name;  // no topology: no counterpart
    }
  }
  return aligned;
}

}  // namespace

std::optional<Frame> ccd_counterparts(const Frame& from, const Frame& to) {
  const auto all_components = [](const Frame& f) {
    return std::all_of(f.objects.begin(), f.objects.end(), [](const Object& o) { return is_component(o); });
  };
  if (!from.objects.empty() && all_components(from) && all_components(to)) return counterparts_by_origin(from, to);
  return counterparts_by_name(from, to);
}

CcdParticipants ccd_participants(const Frame& from, const Frame& to) {
  CcdParticipants p;
  std::unordered_map<std::string, size_t> to_names;  // built when first needed
  for (size_t i = 0; i < from.objects.size(); ++i) {
    const Object& a = from.objects[i];
    const Index id = static_cast<Index>(i);
    if (i >= to.objects.size()) {
      p.skipped.push_back({id, "no counterpart in frame " + std::to_string(to.index) + " (it has " +
                                   std::to_string(to.objects.size()) + " objects)"});
      continue;
    }
    const Object& b = to.objects[i];
    if (!b.topology) {
      if (is_component(a))
        // The mesh's name from the piece's own "<mesh>#k" (a topology kept from an earlier
        // frame keeps that frame's name of a mesh named after its file).
        p.skipped.push_back({id, "no piece of '" + a.name.substr(0, a.name.rfind('#')) + "' in frame " + std::to_string(to.index) +
                                     " holds the same vertices (" + kPieceRule + ")"});
      else
        p.skipped.push_back({id, "no object named '" + a.name + "' in frame " + std::to_string(to.index)});
      continue;
    }
    if (is_component(a) || is_component(b)) {
      // Pieces are matched by their vertices, not by their names (which only number them).
      if (!is_component(a) || !is_component(b) || !same_component(a, b)) {
        p.skipped.push_back({id, "'" + b.name + "' of frame " + std::to_string(to.index) +
                                     " holds other vertices (" + kPieceRule + ")"});
        continue;
      }
    } else if (a.name != b.name) {
      // Objects are matched by position. When this object's name is found at another
      // position of the next frame (and not here), the files list their objects in another
      // order: the vertices here belong to another object. (A name that changes but is not
      // found elsewhere, e.g. one taken from each frame's file name, says nothing.)
      if (to_names.empty())
        for (size_t k = to.objects.size(); k-- > 0;) to_names[to.objects[k].name] = k;  // first wins
      const auto moved = to_names.find(a.name);
      if (moved != to_names.end()) {
        p.skipped.push_back({id, "'" + a.name + "' is object " + std::to_string(moved->second) + " of frame " +
                                     std::to_string(to.index) + ", '" + b.name +
                                     "' takes its place (objects are matched by position)"});
        continue;
      }
    }
    // Faces, not vertex counts: vertices used by no face take no part (an unused vertex
    // added or dropped between the files of an object changes nothing here).
    if (a.topology != b.topology && a.topology->faces != b.topology->faces) {
      std::string reason = "topology changes between frames " + std::to_string(from.index) +
                           " and " + std::to_string(to.index);
      if (a.num_vertices() != b.num_vertices() || a.num_triangles() != b.num_triangles())
        reason += " (" + std::to_string(a.num_vertices()) + " vertices, " +
                  std::to_string(a.num_triangles()) + " faces -> " + std::to_string(b.num_vertices()) +
                  " vertices, " + std::to_string(b.num_triangles()) + " faces)";
      else
        reason += " (same counts, different faces)";
      p.skipped.push_back({id, reason});
      continue;
    }
    p.objects.push_back(id);
  }
  return p;
}

CcdSweep CcdSweep::compute(const Frame& from, const Frame& to, int threads) {
  CcdSweep s;
  s.participants = ccd_participants(from, to);
  const size_t n = from.objects.size();
  s.triangles.assign(n, {});
  s.objects.assign(n, AABB{});
  s.vertices.assign(n, {});
  // Margin from the coordinates of the step (both frames, participating objects).
  AABB all;
  double magnitude = 0;
  for (Index i : s.participants.objects) {
    for (const Frame* f : {&from, &to})
      for (const Vec3& p : f->objects[static_cast<size_t>(i)].positions) {
        all.extend(p);
        magnitude = std::max(magnitude, p.cwiseAbs().maxCoeff());
      }
  }
  const double extent = all.empty() ? 0.0 : (all.hi - all.lo).maxCoeff();
  s.margin = ccd_max_tolerance(extent, magnitude) + rounding_slack(magnitude);
  s.raw_objects.assign(n, AABB{});
  s.magnitudes.assign(n, 0.0);
  s.shares.assign(n, {});
  const auto& ids = s.participants.objects;
  parallel_for(ids.size(), threads, [&](size_t k) {
    const size_t i = static_cast<size_t>(ids[k]);
    const Object& a = from.objects[i];
    const Object& b = to.objects[i];
    auto& vb = s.vertices[i];
    vb.assign(a.positions.size(), AABB{});
    AABB raw;
    // Only the vertices of faces: the two frames may differ in unused ones (which b may lack).
    const Adjacency& adj = adjacency(*a.topology);
    for (size_t v = 0; v < vb.size(); ++v) {
      if (adj.vertex_triangles(static_cast<Index>(v)).empty()) continue;
      vb[v] = swept_box(a, b, {static_cast<Index>(v)});
      raw.extend(vb[v]);
    }
    s.raw_objects[i] = raw;
    if (!raw.empty()) s.magnitudes[i] = box_magnitude(raw);
    // Each triangle's box is widened by its own share of the margin: every query made of two
    // triangles' primitives has its 8 points among their 12 positions, so its δ is bounded by
    // the margin of the two triangles' boxes, and their shares add up to that (ccd.hpp). An
    // object-wide share (1e-6 of the object's size) took in every triangle of a layer stacked
    // closer than that: a 32-layer accordion 1e-6 of an edge apart ran 44M elementary tests.
    auto& tb = s.triangles[i];
    auto& share = s.shares[i];
    tb.resize(static_cast<size_t>(a.num_triangles()));
    share.resize(tb.size());
    AABB box;
    for (Index t = 0; t < a.num_triangles(); ++t) {
      const Face& f = a.topology->faces[static_cast<size_t>(t)];
      AABB tri = vb[static_cast<size_t>(f[0])];
      tri.extend(vb[static_cast<size_t>(f[1])]);
      tri.extend(vb[static_cast<size_t>(f[2])]);
      const double w = margin_share(tri);
      share[static_cast<size_t>(t)] = w;
      tri.lo.array() -= w;
      tri.hi.array() += w;
      tb[static_cast<size_t>(t)] = tri;
      box.extend(tri);
    }
    s.objects[i] = box;
  });
  return s;
}

double ccd_margin_between(const AABB& a, const AABB& b) {
  AABB both = a;
  both.extend(b);
  if (both.empty()) return ccd_max_tolerance(0, 0) + rounding_slack(0);
  const double magnitude = box_magnitude(both);
  return ccd_max_tolerance((both.hi - both.lo).maxCoeff(), magnitude) + rounding_slack(magnitude);
}

double CcdSweep::pair_margin(Index i, Index j) const {
  return ccd_margin_between(raw_objects[static_cast<size_t>(i)], raw_objects[static_cast<size_t>(j)]);
}

CcdStepResult continuous_collisions(const Frame& from, const Frame& to, const CcdOptions& opts) {
  Stopwatch sw;
  const CcdSweep sweep = CcdSweep::compute(from, to, std::max(1, opts.threads));
  const double ms = sw.elapsed_ms();
  CcdStepResult r = continuous_collisions(from, to, sweep, opts);
  r.aabb_ms += ms;
  return r;
}

CcdStepResult continuous_collisions(const Frame& from, const Frame& to, const CcdSweep& sweep,
                                    const CcdOptions& opts) {
  const int threads = std::max(1, opts.threads);
  CcdStepResult out;
  out.to_frame = to.index;
  out.skipped = sweep.participants.skipped;
  Stopwatch sw;

  // Stage I, object level: the object pairs whose swept boxes overlap, and each object with
  // itself.
  std::vector<Index> live;
  for (Index i : sweep.participants.objects)
    if (from.objects[static_cast<size_t>(i)].num_triangles() > 0) live.push_back(i);
  std::vector<std::pair<Index, Index>> object_pairs =
      overlapping_box_pairs(ObjectBoxTree::build(sweep.objects, live), sweep.objects, threads);
  for (Index i : live) object_pairs.emplace_back(i, i);
  std::sort(object_pairs.begin(), object_pairs.end());
  out.counters.object_pairs = object_pairs.size();

  std::vector<TriangleBvh> bvhs(from.objects.size());
  std::vector<Ownership> owners(from.objects.size());
  std::vector<std::vector<Face>> pivot(from.objects.size());
  std::vector<std::vector<std::array<Index, 3>>> node_pivots(from.objects.size());
  std::vector<std::vector<SweptTriangle>> swept(from.objects.size());
  std::vector<EndBoxes> ends(from.objects.size());
  // Per object, in two rounds of independent parts, so that a scene of one big object (a
  // skirt and two legs) still keeps two threads busy: the hierarchy; the ownership and pivots;
  // the swept triangles; then what needs the hierarchy.
  // A hierarchy of at least FrameBoxes::kLargeBvh triangles is built first, on all threads.
  for (Index i : live)
    if (sweep.triangles[static_cast<size_t>(i)].size() >= FrameBoxes::kLargeBvh)
      bvhs[static_cast<size_t>(i)].build(sweep.triangles[static_cast<size_t>(i)], threads);
  parallel_for(3 * live.size(), threads, [&](size_t item) {
    const size_t i = static_cast<size_t>(live[item / 3]);
    if (item % 3 == 0) {
      if (sweep.triangles[i].size() < FrameBoxes::kLargeBvh) bvhs[i].build(sweep.triangles[i]);
    } else if (item % 3 == 1) {
      owners[i] = ownership(*from.objects[i].topology, true);
      pivot[i] = pivots(*from.objects[i].topology, owners[i]);
    } else {
      swept[i] = swept_triangles(from.objects[i], to.objects[i]);
    }
  });
  parallel_for(2 * live.size(), threads, [&](size_t item) {
    const size_t i = static_cast<size_t>(live[item / 2]);
    if (item % 2 == 0) {
      node_pivots[i] = bvhs[i].node_common_vertices(pivot[i]);
    } else {
      ends[i] = EndBoxes::of(swept[i], bvhs[i], sweep.shares[i]);
    }
  });
  out.aabb_ms = sw.elapsed_ms();
  sw.restart();

  // Units of work: (object pair, chunk of the first object's triangles that can meet the
  // second: all of them within one object, else those whose swept boxes overlap the second
  // object's, found through the first one's BVH). Scanning all of them made every small object
  // beside a big one of lower id cost the big one's size: 20,000 tetrahedra on a 161,312-triangle
  // floor listed first took 10.3 s of exact stage against 0.9 s with the floor listed last.
  std::vector<std::vector<Index>> near(object_pairs.size());
  parallel_for(object_pairs.size(), threads, [&](size_t p) {
    const auto [i, j] = object_pairs[p];
    if (i == j) return;
    bvhs[static_cast<size_t>(i)].query_overlaps(sweep.objects[static_cast<size_t>(j)],
                                                [](std::int32_t) { return false; },
                                                [&](Index f) { near[p].push_back(f); });
    std::sort(near[p].begin(), near[p].end());
  });
  // Within one object, the BVH is descended against itself (TriangleBvh::self_overlaps()),
  // from node pairs that split the search into units of work. A pair of subtrees is passed
  // over when a pivot is common to all their triangles (no primitive pair to test below:
  // pivots()) or when they stay apart at both ends of the step, along x, y, z or a diagonal
  // (Diagonals), or, moving fast relative to each other, along the axes perpendicular to that
  // motion.
  std::vector<double> self_margin(from.objects.size(), 0.0);
  for (Index i : live) self_margin[static_cast<size_t>(i)] = sweep.pair_margin(i, i);
  auto self_apart = [&](Index i, std::int32_t a, std::int32_t b) {
    const auto ui = static_cast<size_t>(i);
    const auto ua = static_cast<size_t>(a), ub = static_cast<size_t>(b);
    if (TriangleBvh::adjacent_subtree(node_pivots[ui][ua], node_pivots[ui][ub])) return true;
    if (a == b) return false;
    const EndBoxes& e = ends[ui];
    const double gap = 2 * std::min(self_margin[ui], e.node_share[ua] + e.node_share[ub]);
    const AABB &a_start = e.node_start[ua], &a_end = e.node_end[ua];
    const AABB &b_start = e.node_start[ub], &b_end = e.node_end[ub];
    if (apart_at_both_ends(a_start, a_end, b_start, b_end, gap) ||
        diagonals_apart(e.node_diag_start[ua], e.node_diag_end[ua], e.node_diag_start[ub], e.node_diag_end[ub], gap))
      return true;
    // Subtrees moving fast relative to each other (by more than twice the larger one's size):
    // the axes perpendicular to that motion, as in swept_apart().
    const Vec3 r = 0.5 * (((a_end.lo + a_end.hi) - (a_start.lo + a_start.hi)) - ((b_end.lo + b_end.hi) - (b_start.lo + b_start.hi)));
    const double size = std::max((a_start.hi - a_start.lo).maxCoeff(), (b_start.hi - b_start.lo).maxCoeff());
    if (!(r.squaredNorm() > 4 * size * size)) return false;
    const auto w = perpendicular_axes(r);
    return boxes_apart_along(a_start, a_end, b_start, b_end, w[0], gap) ||
           boxes_apart_along(a_start, a_end, b_start, b_end, w[1], gap);
  };
  std::vector<std::vector<TriangleBvh::NodePair>> self_pairs(object_pairs.size());
  parallel_for(object_pairs.size(), threads, [&](size_t p) {
    const Index i = object_pairs[p].first;
    if (i != object_pairs[p].second) return;
    self_pairs[p] = bvhs[static_cast<size_t>(i)].self_overlap_pairs(
        kChunk, [&](std::int32_t a, std::int32_t b) { return self_apart(i, a, b); });
  });
  struct Task {
    Index i, j;
    std::size_t pair;    ///< index into object_pairs (and near, self_pairs)
    Index first, last;  ///< within self_pairs[pair] (i == j), else within near[pair]
  };
  std::vector<Task> tasks;
  for (size_t p = 0; p < object_pairs.size(); ++p) {
    const auto [i, j] = object_pairs[p];
    if (i == j) {  // a task per node pair (of at most kChunk triangles)
      for (Index q = 0; q < static_cast<Index>(self_pairs[p].size()); ++q) tasks.push_back({i, j, p, q, q + 1});
      continue;
    }
    const auto n = static_cast<Index>(near[p].size());
    for (Index t = 0; t < n; t += kChunk) tasks.push_back({i, j, p, t, std::min(n, t + kChunk)});
  }
  const Tester tester(from, to);
  // Stage II runs on the inter-object triangle pairs that Stage I leaves: pairs not shown
  // apart, with at least one primitive pair not shown apart. It is given by the caller, or
  // built here over those pairs' triangles once Stage I has listed them: a reportable primitive
  // pair is tested in its owner triangles' pair, which is then listed, so both triangles are
  // voxelized and the culling argument of ccd_stage2.hpp holds for it. Without Stage II, and
  // for pairs within one object, each pair goes straight to its primitive tests.
  //   Stage II culls inter-object pairs only. Within one object it ruled out almost nothing
  // while most of the triangles it voxelized were there for such pairs alone: on the report
  // scenes' steps 10-18 (2 threads, sums over the 9 steps) it culled 0-66 of 1,279-103,966
  // pairs within objects (between objects it rules out 0-34 there), and leaving those pairs
  // out takes the voxelized triangles per step from 713 to 572 (skirt), 1,797 to 76
  // (cloth-ball), 634 to 89 (bowl), 7,419 to 975 (funnel) and 1,108 to 1,058 (breaking).
  // docs/algorithms.md, "Continuous collision detection", has the times.
  const CcdVoxelCulling* voxels = opts.voxels;
  const bool stage2 = voxels || opts.voxel_backend;
  struct Candidate {
    Index f, g;
    std::uint16_t mask;  ///< its primitive pairs to test (cull_pair())
  };
  std::vector<std::vector<Candidate>> candidates(stage2 ? tasks.size() : 0);
  std::vector<Hits> parts(tasks.size());
  // Stage I of task k (stage2: its candidate pairs are listed), or Stage III of its listed pairs
  // after Stage II's checks (replay).
  auto process = [&](size_t k, bool replay) {
    const Task& task = tasks[k];
    const Index i = task.i, j = task.j;
    const Object& oi = from.objects[static_cast<size_t>(i)];
    const Object& oj = from.objects[static_cast<size_t>(j)];
    const Object& ti = to.objects[static_cast<size_t>(i)];
    const Object& tj = to.objects[static_cast<size_t>(j)];
    const Adjacency& adj_i = adjacency(*oi.topology);
    const Adjacency& adj_j = adjacency(*oj.topology);
    const Ownership& own_i = owners[static_cast<size_t>(i)];
    const Ownership& own_j = owners[static_cast<size_t>(j)];
    const auto& tb_i = sweep.triangles[static_cast<size_t>(i)];
    const auto& vb_i = sweep.vertices[static_cast<size_t>(i)];
    const auto& vb_j = sweep.vertices[static_cast<size_t>(j)];
    const auto& swept_i = swept[static_cast<size_t>(i)];
    const auto& swept_j = swept[static_cast<size_t>(j)];
    const EndBoxes& ends_i = ends[static_cast<size_t>(i)];
    const EndBoxes& ends_j = ends[static_cast<size_t>(j)];
    // A segment's swept box: the union of its two vertices' (the same min/max as boxing all
    // four positions).
    auto edge_box = [](const std::vector<AABB>& vb, const std::array<Index, 2>& e) {
      AABB box = vb[static_cast<size_t>(e[0])];
      box.extend(vb[static_cast<size_t>(e[1])]);
      return box;
    };
    // A triangle's swept box, not widened.
    auto raw_box = [](const std::vector<AABB>& vb, const Face& f) {
      AABB box = vb[static_cast<size_t>(f[0])];
      box.extend(vb[static_cast<size_t>(f[1])]);
      box.extend(vb[static_cast<size_t>(f[2])]);
      return box;
    };
    const bool self = i == j;
    Hits& hits = parts[k];
    // Separation that rules out a report: the kernel reports a pair whose primitives come
    // within δ_k on every axis (at most sqrt(3) δmax apart), and margin >= δmax + slack. The
    // margin is the sum of the shares of the two triangles at hand, or of a triangle and a
    // BVH subtree (EndBoxes), or the object pair's margin when smaller (both are valid; far
    // from the origin the rounding slack dominates, and each share carries its own).
    const double object_margin = sweep.pair_margin(i, j);
    auto pair_margin = [&](Index f, Index g) {
      return std::min(object_margin, ends_i.share[static_cast<size_t>(f)] + ends_j.share[static_cast<size_t>(g)]);
    };

    // What the culling makes of a primitive pair: no test (boxes apart, or a vertex of the
    // face itself), shown apart along a separating axis, or an elementary test to run.
    enum class Cull { none, apart, test };
    // Vertex v of object ov against a face (its vertex ids, swept box and swept triangle).
    auto vertex_face = [&](Index ov, const std::vector<AABB>& v_boxes, Index v, const Face& g_face,
                           const AABB& g_raw, const SweptTriangle& g_swept, double margin) {
      if (self && in_face(v, g_face)) return Cull::none;
      // The vertex's own swept box, widened by the pair's margin, against the face's.
      AABB vbox = v_boxes[static_cast<size_t>(v)];
      vbox.lo.array() -= margin;
      vbox.hi.array() += margin;
      if (!boxes_overlap(vbox, g_raw)) return Cull::none;
      const SweptPrimitives<1, 3> p{{from.objects[static_cast<size_t>(ov)].positions[static_cast<size_t>(v)]},
                                    {to.objects[static_cast<size_t>(ov)].positions[static_cast<size_t>(v)]},
                                    g_swept.start, g_swept.end};
      if (primitives_apart(p, {g_swept.normal, g_swept.normal_end}, 2 * margin)) return Cull::apart;
      // A vertex beside the face in (or near) its plane, as in a flat mesh around a shared
      // vertex or edge, is apart along none of those: the face's in-plane edge normals at the
      // start (normal x edge) separate it when it stays outside one edge.
      const auto& t = g_swept.start;
      const bool beside = apart_along_any(p, 3, [&](int e) {
        return g_swept.normal.cross(t[static_cast<size_t>((e + 1) % 3)] - t[static_cast<size_t>(e)]);
      }, 2 * margin);
      return beside ? Cull::apart : Cull::test;
    };

    // The primitive pairs of a candidate triangle pair that the culling leaves, as a mask:
    // bits 0-2 f's owned vertices against g, 3-5 g's against f, 6 + 3 ka + kb f's owned edge ka
    // against g's kb. Counts the pairs it shows apart.
    auto cull_pair = [&](Index f, Index g) {
      const double margin = pair_margin(f, g);
      const Face& ff = oi.topology->faces[static_cast<size_t>(f)];
      const Face& gf = oj.topology->faces[static_cast<size_t>(g)];
      const AABB f_raw = raw_box(vb_i, ff);
      const AABB g_raw = raw_box(vb_j, gf);
      const SweptTriangle& swept_f = swept_i[static_cast<size_t>(f)];
      const SweptTriangle& swept_g = swept_j[static_cast<size_t>(g)];
      std::uint16_t mask = 0;
      auto note = [&](Cull r, int bit) {
        if (r == Cull::apart) ++hits.counters.separated_primitives;
        if (r == Cull::test) mask = static_cast<std::uint16_t>(mask | (1u << bit));
      };
      for (size_t c = 0; c < 3; ++c)
        if (own_i.vertex[static_cast<size_t>(ff[c])] == f && !repeats_earlier(ff, c))
          note(vertex_face(i, vb_i, ff[c], gf, g_raw, swept_g, margin), static_cast<int>(c));
      for (size_t c = 0; c < 3; ++c)
        if (own_j.vertex[static_cast<size_t>(gf[c])] == g && !repeats_earlier(gf, c))
          note(vertex_face(j, vb_j, gf[c], ff, f_raw, swept_f, margin), static_cast<int>(3 + c));
      const auto& fe = adj_i.triangle_edges(f);
      const auto& ge = adj_j.triangle_edges(g);
      for (size_t ka = 0; ka < 3; ++ka) {
        const Index ea = fe[ka];
        if (ea == kNoIndex || own_i.edge[static_cast<size_t>(ea)] != f || repeats_earlier(fe, ka)) continue;
        const auto& va = adj_i.edges()[static_cast<size_t>(ea)];
        const AABB ba = edge_box(vb_i, va);
        for (size_t kb = 0; kb < 3; ++kb) {
          const Index eb = ge[kb];
          if (eb == kNoIndex || own_j.edge[static_cast<size_t>(eb)] != g || repeats_earlier(ge, kb)) continue;
          const auto& vb = adj_j.edges()[static_cast<size_t>(eb)];
          if (self && share_endpoint(va, vb)) continue;
          AABB bb = edge_box(vb_j, vb);
          bb.lo.array() -= margin;
          bb.hi.array() += margin;
          if (!boxes_overlap(ba, bb)) continue;
          auto ends = [](const Object& o, const std::array<Index, 2>& e) {
            return std::array<Vec3, 2>{o.positions[static_cast<size_t>(e[0])], o.positions[static_cast<size_t>(e[1])]};
          };
          const SweptPrimitives<2, 2> p{ends(oi, va), ends(ti, va), ends(oj, vb), ends(tj, vb)};
          const Vec3 cross_start = (p.a_start[1] - p.a_start[0]).cross(p.b_start[1] - p.b_start[0]);
          const Vec3 cross_end = (p.a_end[1] - p.a_end[0]).cross(p.b_end[1] - p.b_end[0]);
          // Then, for two edges side by side in a plane (where cross_start is its normal), each
          // edge's in-plane normal at the start (edge x cross_start).
          const bool apart =
              primitives_apart(p, {cross_start, cross_end}, 2 * margin) ||
              apart_along_any(p, 2, [&](int e) {
                const auto& edge = e == 0 ? p.a_start : p.b_start;
                return (edge[1] - edge[0]).cross(cross_start);
              }, 2 * margin);
          note(apart ? Cull::apart : Cull::test, static_cast<int>(6 + 3 * ka + kb));
        }
      }
      return mask;
    };
    // Stage III: the elementary tests of the primitive pairs in `mask` (from cull_pair()).
    auto run_tests = [&](Index f, Index g, std::uint16_t mask) {
      const Face& ff = oi.topology->faces[static_cast<size_t>(f)];
      const Face& gf = oj.topology->faces[static_cast<size_t>(g)];
      for (size_t c = 0; c < 3; ++c)
        if (mask & (1u << c)) tester.vertex_face(i, ff[c], j, g, hits);
      for (size_t c = 0; c < 3; ++c)
        if (mask & (1u << (3 + c))) tester.vertex_face(j, gf[c], i, f, hits);
      const auto& fe = adj_i.triangle_edges(f);
      const auto& ge = adj_j.triangle_edges(g);
      for (size_t ka = 0; ka < 3; ++ka)
        for (size_t kb = 0; kb < 3; ++kb) {
          if (!(mask & (1u << (6 + 3 * ka + kb)))) continue;
          const Index ea = fe[ka], eb = ge[kb];
          const auto& va = adj_i.edges()[static_cast<size_t>(ea)];
          const auto& vb = adj_j.edges()[static_cast<size_t>(eb)];
          // Canonical order: the smaller (object, edge id) first.
          if (i < j || (self && ea < eb))
            tester.edge_edge(i, va, j, vb, hits);
          else
            tester.edge_edge(j, vb, i, va, hits);
        }
    };

    if (replay) {
      // Stage II's checks, then Stage III (only inter-object tasks list candidates): a triangle
      // none of whose keys another object marks takes part in no collision (counted once per
      // triangle and task, the pairs of its run all dropped); then the pair must share a key.
      Index last_f = kNoIndex;
      bool f_kept = true;
      for (const Candidate& cand : candidates[k]) {
        const Index f = cand.f, g = cand.g;
        if (f != last_f) {
          last_f = f;
          f_kept = voxels->keeps(i, f);
          if (!f_kept) ++hits.counters.culled_triangles;
        }
        if (!f_kept || !voxels->keeps(j, g)) {
          ++hits.counters.unshared_pairs;
          continue;
        }
        if (!voxels->share_voxel(i, f, j, g)) {
          ++hits.counters.unshared_pairs;
          continue;
        }
        run_tests(f, g, cand.mask);
      }
      return;
    }

    // A triangle pair whose swept boxes overlap (within one object, f < g): counted, tried as
    // wholes, then its primitive pairs are culled; those left are tested now, or with Stage
    // II listed for it and tested after it.
    auto candidate_pair = [&](Index f, Index g) {
      if (self && TriangleBvh::adjacent_subtree(pivot[static_cast<size_t>(j)][static_cast<size_t>(g)],
                                                pivot[static_cast<size_t>(i)][static_cast<size_t>(f)]))
        return;  // a common pivot: no primitive pair to test
      ++hits.counters.triangle_pairs;
      const double apart_gap = 2 * pair_margin(f, g);
      // Two triangles of one object that share a vertex are never apart as wholes (both
      // boxes and both projections on any axis contain that vertex's), so only their
      // primitive pairs are tried (88% of the pairs that reach cull_pair() on the funnel
      // scene's frames 10-19, 94% on cloth-ball's); but when they share one vertex only, one
      // axis may show all of those apart at once (apart_around_vertex(), counted as a
      // separated pair). On steps 10-18 (2 threads) that took the primitive pairs culled one by
      // one from 330,974 to 152,027 per step on funnel and from 154,314 to 35,690 on
      // cloth-ball, and CCD's exact stage from 18.4 to 16.5 ms there (funnel: within its spread).
      const Face& ff = oi.topology->faces[static_cast<size_t>(f)];
      const Face& gf = oj.topology->faces[static_cast<size_t>(g)];
      // Corners the two have in common (within one object), and where the last one is in each.
      int common = 0, fc = 0, gc = 0;
      if (self)
        for (int x = 0; x < 3; ++x)
          for (int y = 0; y < 3; ++y)
            if (ff[static_cast<size_t>(x)] == gf[static_cast<size_t>(y)]) {
              ++common;
              fc = x;
              gc = y;
            }
      const bool touching = common > 0;
      if (touching) {
        // Exactly one common vertex c (and three distinct corners each): f's other two
        // corners against g's, around c (apart_around_vertex()).
        const bool distinct = ff[0] != ff[1] && ff[1] != ff[2] && ff[0] != ff[2] && gf[0] != gf[1] && gf[1] != gf[2] && gf[0] != gf[2];
        if (common == 1 && distinct) {
          auto others = [](const Object& o, const Face& face, int skip) {
            return std::array<Vec3, 2>{o.positions[static_cast<size_t>(face[static_cast<size_t>((skip + 1) % 3)])],
                                       o.positions[static_cast<size_t>(face[static_cast<size_t>((skip + 2) % 3)])]};
          };
          const auto c = static_cast<size_t>(ff[static_cast<size_t>(fc)]);
          if (apart_around_vertex(others(oi, ff, fc), others(ti, ff, fc), others(oj, gf, gc), others(tj, gf, gc),
                                  oi.positions[c], ti.positions[c], apart_gap)) {
            ++hits.counters.separated_pairs;
            return;
          }
        }
      }
      if (!touching && (apart_at_both_ends(ends_i.start[static_cast<size_t>(f)], ends_i.end[static_cast<size_t>(f)],
                                           ends_j.start[static_cast<size_t>(g)], ends_j.end[static_cast<size_t>(g)], apart_gap) ||
                        diagonals_apart(ends_i.diag_start[static_cast<size_t>(f)],
                                        ends_i.diag_end[static_cast<size_t>(f)],
                                        ends_j.diag_start[static_cast<size_t>(g)],
                                        ends_j.diag_end[static_cast<size_t>(g)], apart_gap) ||
                        swept_apart(swept_i[static_cast<size_t>(f)], swept_j[static_cast<size_t>(g)], apart_gap))) {
        ++hits.counters.separated_pairs;
        return;
      }
      const std::uint16_t mask = cull_pair(f, g);
      if (mask == 0) return;
      // Stage II looks at inter-object pairs only (see `stage2` above): two triangles of one
      // object that Stage I leaves are close in space and time, nearly always sharing a key.
      if (stage2 && !self)
        candidates[k].push_back({f, g, mask});
      else
        run_tests(f, g, mask);
    };

    if (self) {
      const TriangleBvh& bvh = bvhs[static_cast<size_t>(i)];
      const auto apart = [&](std::int32_t a, std::int32_t b) { return self_apart(i, a, b); };
      for (Index q = task.first; q < task.last; ++q)
        bvh.self_overlaps(self_pairs[task.pair][static_cast<size_t>(q)], apart,
                          [&](Index f, Index g) { candidate_pair(std::min(f, g), std::max(f, g)); });
      return;
    }
    for (Index q = task.first; q < task.last; ++q) {
      const Index f = near[task.pair][static_cast<size_t>(q)];
      const AABB& fb = tb_i[static_cast<size_t>(f)];
      const SweptTriangle& swept_f = swept_i[static_cast<size_t>(f)];
      const AABB& f_start = ends_i.start[static_cast<size_t>(f)];
      const AABB& f_end = ends_i.end[static_cast<size_t>(f)];
      const double f_share = ends_i.share[static_cast<size_t>(f)];
      const Vec3 f_motion = 0.5 * ((f_end.lo + f_end.hi) - (f_start.lo + f_start.hi));  // its box center's
      const auto subtree_apart = [&](std::int32_t node) {
        const AABB& n_start = ends_j.node_start[static_cast<size_t>(node)];
        const AABB& n_end = ends_j.node_end[static_cast<size_t>(node)];
        const double apart_gap = 2 * std::min(object_margin, f_share + ends_j.node_share[static_cast<size_t>(node)]);
        if (apart_at_both_ends(f_start, f_end, n_start, n_end, apart_gap) ||
            diagonals_apart(ends_i.diag_start[static_cast<size_t>(f)], ends_i.diag_end[static_cast<size_t>(f)],
                            ends_j.node_diag_start[static_cast<size_t>(node)],
                            ends_j.node_diag_end[static_cast<size_t>(node)], apart_gap))
          return true;
        // A triangle moving fast relative to the subtree (by more than twice its own size):
        // the axes perpendicular to that motion, as in swept_apart().
        const Vec3 r = f_motion - 0.5 * ((n_end.lo + n_end.hi) - (n_start.lo + n_start.hi));
        if (!(r.squaredNorm() > 4 * swept_f.size * swept_f.size)) return false;
        const auto w = perpendicular_axes(r);
        return boxes_apart_along(f_start, f_end, n_start, n_end, w[0], apart_gap) ||
               boxes_apart_along(f_start, f_end, n_start, n_end, w[1], apart_gap);
      };
      bvhs[static_cast<size_t>(j)].query_overlaps(fb, subtree_apart, [&](Index g) { candidate_pair(f, g); });
    }
  };
  parallel_for(tasks.size(), threads, [&](size_t k) { process(k, false); });
  if (stage2) {
    // Stage II over the triangles of the listed pairs, unless the caller built it.
    std::unique_ptr<CcdVoxelCulling> built;
    out.stage2 = true;
    bool any = false;
    for (const auto& c : candidates) any = any || !c.empty();
    if (!voxels && any) {
      const double stage1_ms = sw.elapsed_ms();
      Stopwatch stage2_sw;
      CcdTriangleMask used(from.objects.size());
      for (Index i : live) used[static_cast<size_t>(i)].assign(static_cast<size_t>(from.objects[static_cast<size_t>(i)].num_triangles()), 0);
      for (size_t k = 0; k < tasks.size(); ++k)
        for (const Candidate& c : candidates[k]) {
          used[static_cast<size_t>(tasks[k].i)][static_cast<size_t>(c.f)] = 1;
          used[static_cast<size_t>(tasks[k].j)][static_cast<size_t>(c.g)] = 1;
        }
      built = std::make_unique<CcdVoxelCulling>(from, to, sweep, CcdVoxelOptions{opts.voxel_grid, opts.voxel_slots, threads},
                                                *opts.voxel_backend, &used);
      voxels = built.get();
      out.voronoi_ms = stage2_sw.elapsed_ms();
      out.voxel_grid = voxels->grid().dims;
      out.voxel_cell = voxels->grid().cell;
      out.counters.voxelized_triangles = voxels->voxelized_triangles();
      sw.restart();
      out.exact_ms = stage1_ms;
    }
    if (any) parallel_for(tasks.size(), threads, [&](size_t k) { process(k, true); });
  }
  finish(parts, out);
  out.exact_ms += sw.elapsed_ms();
  return out;
}

CcdStepResult continuous_collisions_brute_force(const Frame& from, const Frame& to) {
  CcdStepResult out;
  out.to_frame = to.index;
  const CcdParticipants p = ccd_participants(from, to);
  out.skipped = p.skipped;
  const Tester tester(from, to);
  std::vector<Hits> parts(1);
  Hits& hits = parts[0];
  for (size_t a = 0; a < p.objects.size(); ++a) {
    for (size_t b = a; b < p.objects.size(); ++b) {
      const Index i = p.objects[a], j = p.objects[b];
      const Topology& ti = *from.objects[static_cast<size_t>(i)].topology;
      const Topology& tj = *from.objects[static_cast<size_t>(j)].topology;
      const Ownership oi = ownership(ti), oj = ownership(tj);
      const Adjacency& ai = adjacency(ti);
      const Adjacency& aj = adjacency(tj);
      // Vertices of i against faces of j and, for two objects, vertices of j against faces of i.
      auto vf = [&](Index ov, const Ownership& own, Index of, const Topology& tf) {
        for (Index v = 0; v < static_cast<Index>(own.vertex.size()); ++v) {
          if (own.vertex[static_cast<size_t>(v)] == kNoIndex) continue;
          for (Index g = 0; g < tf.num_triangles(); ++g) {
            if (ov == of && in_face(v, tf.faces[static_cast<size_t>(g)])) continue;
            tester.vertex_face(ov, v, of, g, hits);
          }
        }
      };
      vf(i, oi, j, tj);
      if (i != j) vf(j, oj, i, ti);
      for (size_t ea = 0; ea < ai.edges().size(); ++ea)
        for (size_t eb = (i == j ? ea + 1 : 0); eb < aj.edges().size(); ++eb) {
          if (i == j && share_endpoint(ai.edges()[ea], aj.edges()[eb])) continue;
          tester.edge_edge(i, ai.edges()[ea], j, aj.edges()[eb], hits);
        }
    }
  }
  finish(parts, out);
  return out;
}

}  // namespace vproxq
