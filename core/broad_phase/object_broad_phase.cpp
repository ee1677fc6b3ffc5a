#include "core/broad_phase/object_broad_phase.hpp"

#include "core/broad_phase/sorted_axis.hpp"
#include "core/broad_phase/triangle_bvh.hpp"
#include "core/geometry/point_triangle.hpp"
#include "core/geometry/triangle_distance.hpp"
#include "core/mesh/adjacency.hpp"
#include "core/parallel.hpp"

#include <algorithm>
#include <array>
#include <cstddef>
#include <cmath>

namespace vproxq {
namespace {

// See rounding_slack(): ~4.5e5 ulps of the coordinate magnitude (2^-52 ~ 2.2e-16).
constexpr double kSlackPerMagnitude = 1e-10;
// The absolute part of rounding_slack(): underflow. Squared distances lose at most a few
// multiples of 2^-1074 to it, which is below 2^-530 after the square root; 2^-500 covers that
// and is negligible at every scale a scene can have (nonzero coordinates are at least 2^-200
// in magnitude, types.hpp). An absolute part of the size of kSlackPerMagnitude instead made
// the slack larger than the whole scene below ~1e-10 scale (every box then overlapped every
// other, and CCD's voxel culling ran out of memory).
constexpr double kSlackAbsolute = 0x1p-500;
// U_i is computed in double from a few subtractions, squares and a sqrt (< 10 roundings);
// widening it by 1e-12 relative keeps it an upper bound of the exact value.
constexpr double kUpperBoundWidening = 1e-12;

/// The triangle corner of `o` nearest to p (over corners of faces only: isolated vertices
/// are not part of the surface), through the object's BVH (`bvh`, over its triangles' boxes);
/// ties go to the first face, then the first corner in it, as a scan of every face would pick.
/// A scan made Stage I linear in a candidate's size per object: 1.8 s per frame for 5,000
/// small objects over a 180,000-triangle ground that most of them had as a candidate.
struct Corner {
  Vec3 p = Vec3::Zero();
  Index vertex = kNoIndex;
};
Corner nearest_corner(const Object& o, const TriangleBvh& bvh, const Vec3& p) {
  double best = kInfinity;
  Index best_t = kNoIndex;
  int best_c = 0;
  Corner best_p;
  AABB point;
  point.extend(p);
  // Widened so that rounding in the box distances cannot prune a leaf holding a tie.
  const auto bound = [&] { return std::sqrt(best) * (1 + 1e-9); };
  bvh.query(point, bound, [&](Index t, double) {
    const Face& f = o.topology->faces[static_cast<size_t>(t)];
    for (int c = 0; c < 3; ++c) {
      const Vec3& q = o.positions[static_cast<size_t>(f[static_cast<size_t>(c)])];
      const double d = (q - p).squaredNorm();
      if (d < best || (d == best && (t < best_t || (t == best_t && c < best_c)))) {
        best = d;
        best_t = t;
        best_c = c;
        best_p = {q, f[static_cast<size_t>(c)]};
      }
    }
  });
  return best_p;
}

/// Corners with more incident triangles than this are not probed for contact, and a probe
/// tests at most kContactProbeTriangles triangles of the other object against them.
constexpr std::size_t kContactProbeValence = 16;
constexpr int kContactProbeTriangles = 16;
/// Objects whose boxes overlap i's that Stage I also walks to (probing for contact), besides
/// the candidates of U_i, while no contact is found. The candidates are often not the object
/// i touches (of many boxes at distance 0, the nearest box is the one of smallest id): on the
/// 200-object scene's frames 3 and 4 they prove contact for 21 of 46 and 58 of 93 touching
/// objects, with up to 4 more walks 46 and 92 (2: 43 and 86; 8: 46 and 93).
constexpr int kContactWalks = 4;

/// Whether a triangle incident to corner vb of b meets one of a's triangles whose boxes
/// overlap theirs (the first kContactProbeTriangles that a's BVH lists; exact tests): then the
/// objects touch. False says nothing.
bool corner_touches(const Object& oa, const TriangleBvh& bvh_a, const Object& ob,
                    const std::vector<AABB>& boxes_b, Index vb) {
  if (vb == kNoIndex) return false;
  const IndexSpan around = adjacency(*ob.topology).vertex_triangles(vb);
  if (around.size() > kContactProbeValence) return false;
  AABB box;
  for (const Index t : around) box.extend(boxes_b[static_cast<size_t>(t)]);
  bool found = false;
  int probed = 0;
  const auto done = [&] { return found || probed >= kContactProbeTriangles; };
  bvh_a.query_overlaps(box, [&](std::int32_t) { return done(); }, [&](Index s) {
    if (done()) return;
    ++probed;
    const Triangle ts = oa.triangle(s);
    for (const Index t : around)
      if (triangles_intersect(ts, ob.triangle(t))) {
        found = true;
        return;
      }
  });
  return found;
}

/// Distance of a pair of surface points of objects a and b found by walking to nearest
/// corners: an upper bound on the distance between the objects. When the triangles around
/// the two corners meet, the objects touch and the bound is 0: interpenetrating objects are
/// nearest where their surfaces cross, so a walk often ends there, and a bound of 0 makes the
/// later stages look only at boxes that touch (on the 200-object scene, frames 3 and 4 have
/// 46 and 93 objects touching another).
double vertex_walk_bound(const Frame& frame, const FrameBoxes& boxes, Index a, Index b) {
  const Object& oa = frame.objects[static_cast<size_t>(a)];
  const Object& ob = frame.objects[static_cast<size_t>(b)];
  const TriangleBvh& ba = boxes.bvh(static_cast<size_t>(a));
  const TriangleBvh& bb = boxes.bvh(static_cast<size_t>(b));
  const Corner v = nearest_corner(oa, ba, boxes.objects[static_cast<size_t>(b)].center());
  const Corner w = nearest_corner(ob, bb, v.p);
  const Corner v2 = nearest_corner(oa, ba, w.p);
  if (boxes_overlap(boxes.objects[static_cast<size_t>(a)], boxes.objects[static_cast<size_t>(b)]) &&
      (corner_touches(oa, ba, ob, boxes.triangles[static_cast<size_t>(b)], w.vertex) ||
       corner_touches(ob, bb, oa, boxes.triangles[static_cast<size_t>(a)], v2.vertex)))
    return 0;
  return (v2.p - w.p).norm();
}

}  // namespace

double rounding_slack(double magnitude) { return kSlackPerMagnitude * magnitude + kSlackAbsolute; }

FrameBoxes FrameBoxes::compute(const Frame& frame, int threads) {
  FrameBoxes fb;
  const size_t n = frame.objects.size();
  fb.triangles.resize(n);
  fb.objects.assign(n, AABB{});
  std::vector<double> mags(n, 0.0);
  parallel_for(n, threads, [&](size_t i) {
    const Object& o = frame.objects[i];
    auto& tb = fb.triangles[i];
    tb.resize(static_cast<size_t>(o.num_triangles()));
    AABB box;
    for (Index t = 0; t < o.num_triangles(); ++t) {
      tb[static_cast<size_t>(t)] = AABB::of(o.triangle(t));
      box.extend(tb[static_cast<size_t>(t)]);
    }
    fb.objects[i] = box;
    if (!box.empty()) mags[i] = std::max(box.lo.cwiseAbs().maxCoeff(), box.hi.cwiseAbs().maxCoeff());
  });
  for (double m : mags) fb.magnitude = std::max(fb.magnitude, m);
  fb.magnitudes = std::move(mags);
  fb.bvh_cache = std::make_shared<BvhCache>(n);
  return fb;
}

namespace {

const Enclosure& enclosure(const Frame& frame, const FrameBoxes& boxes, size_t i) {
  FrameBoxes::BvhCache& cache = *boxes.bvh_cache;
  std::call_once(cache.enclosure_once[i], [&] {
    const Object& o = frame.objects[i];
    const Vec3 c = boxes.objects[i].center();
    AABB point;
    point.extend(c);
    double outer2 = 0, inner2 = kInfinity;
    const double margin = 0x1p-40 * boxes.magnitudes[i];
    for (Index t = 0; t < o.num_triangles(); ++t) {
      const Triangle tri = o.triangle(t);
      for (const Vec3& v : tri) outer2 = std::max(outer2, (v - c).squaredNorm());
      // A triangle whose box is no nearer than the nearest triangle so far cannot lower it
      // (the box distance is exact up to one rounding, below the triangle's distance).
      if (box_distance_squared(point, boxes.triangles[i][static_cast<size_t>(t)]) > inner2) continue;
      // Nor can one whose plane lies farther from c than the nearest so far by a margin: the
      // plane's distance P is at most the triangle's D; computed, P is off by less than 2^-46 M
      // (M: the object's magnitude, which bounds c and the corners; a dot product of
      // differences, then one division and a square root) and D by less than 2^-49 M
      // (triangle_distance.cpp), so a plane more than 2^-40 M beyond sqrt(inner2) means a
      // computed D above it, and inner2 stays bitwise the minimum over all triangles. On a
      // rounded shape almost every triangle faces c, and this skips it for the cost of a
      // cross product instead of a point-triangle distance (an exactly rounded normal first).
      // (Normals whose n . n is below 2^-900 or not finite are not used: no underflow enters.)
      const Vec3 n = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
      const double nn = n.squaredNorm();
      if (nn >= 0x1p-900 && std::isfinite(nn) && std::fabs(n.dot(c - tri[0])) / std::sqrt(nn) > std::sqrt(inner2) + margin)
        continue;
      // The computed closest point lies on the triangle up to coordinate rounding, so this is
      // at most a few ulps of the magnitude above the exact distance (rounding_slack() covers it).
      inner2 = std::min(inner2, point_triangle_distance(c, tri).squared_distance);
    }
    cache.enclosures[i] = {c, std::sqrt(outer2), std::sqrt(inner2)};
  });
  return cache.enclosures[i];
}

}  // namespace

double enclosure_lower_bound(const Frame& frame, const FrameBoxes& boxes, Index i, Index j) {
  const auto a = static_cast<size_t>(i), b = static_cast<size_t>(j);
  if (boxes.objects[a].empty() || boxes.objects[b].empty()) return 0;
  const Enclosure& ea = enclosure(frame, boxes, a);
  const Enclosure& eb = enclosure(frame, boxes, b);
  // Each term is within a few ulps of its exact value (at most ~4 times the coordinates'
  // magnitude), far inside the rounding slack of their magnitude.
  const double apart = (ea.center - eb.center).norm();
  const double lb = std::max(eb.inner - apart - ea.outer, ea.inner - apart - eb.outer);
  return std::max(0.0, lb - rounding_slack(std::max(boxes.magnitudes[a], boxes.magnitudes[b])));
}

ObjectBroadPhase object_broad_phase(const Frame& frame, const FrameBoxes& boxes, int threads) {
  const size_t n = frame.objects.size();
  ObjectBroadPhase out;
  out.upper_bound.assign(n, kInfinity);
  out.pns.assign(n, {});
  const double slack = rounding_slack(boxes.magnitude);

  // A hierarchy of the boxes of the objects with triangles (leaf t is object live[t]), and
  // their sorted intervals per axis (Cohen et al. 1995).
  const ObjectBoxTree& object_tree = boxes.object_tree();
  const std::vector<Index>& live = object_tree.ids;
  const TriangleBvh& tree = object_tree.bvh;
  if (live.size() < 2) return out;
  const std::array<SortedAxis, 3> axes{SortedAxis(live, boxes.objects, 0), SortedAxis(live, boxes.objects, 1),
                                       SortedAxis(live, boxes.objects, 2)};
  // The walks below read the triangle BVHs; a large one is built here on all threads rather
  // than by the first walk that needs it, on one.
  boxes.build_bvhs(threads, [&](size_t i) { return boxes.triangles[i].size() >= FrameBoxes::kLargeBvh; });

  parallel_for(live.size(), threads, [&](size_t li) {
    const Index i = live[li];
    const AABB& bi = boxes.objects[static_cast<size_t>(i)];
    // Potentially closest object along each axis.
    std::array<Index, 3> cand{kNoIndex, kNoIndex, kNoIndex};
    for (int k = 0; k < 3; ++k) cand[k] = axes[k].most_overlapping(i);
    double u = kInfinity;
    for (int k = 0; k < 3; ++k) {
      const Index j = cand[k];
      if (j == kNoIndex || (k > 0 && (j == cand[0] || (k > 1 && j == cand[1])))) continue;
      const AABB& bj = boxes.objects[static_cast<size_t>(j)];
      u = std::min(u, box_max_distance(bi, bj));
      u = std::min(u, vertex_walk_bound(frame, boxes, i, j));
    }
    // The box nearest to i's, walked to. For elongated objects side by side, the axis rule may
    // pick one far off along the other axes, and every box's farthest corner (below) is an
    // object's length away: without this walk, U_i held most of N parallel sticks, and so did
    // the PNS and the farthest-corner search below (Stage I was quadratic, 16 s at N = 20,000).
    Index closest = kNoIndex;
    double closest_d2 = kInfinity, closest_d = kInfinity;
    tree.query(bi, [&] { return closest_d; }, [&](Index t, double d2) {
      const Index j = live[static_cast<size_t>(t)];
      if (j != i && (d2 < closest_d2 || (d2 == closest_d2 && j < closest))) {
        closest_d2 = d2;
        closest_d = std::sqrt(d2);
        closest = j;
      }
    });
    if (closest != kNoIndex && closest != cand[0] && closest != cand[1] && closest != cand[2])
      u = std::min(u, vertex_walk_bound(frame, boxes, i, closest));
    // The axis rule can pick an object that overlaps i along one axis and is far away along
    // the others (in a crowd of small objects, most of the time). The box whose farthest
    // corner is nearest also bounds U_i; find it through the hierarchy, and walk to it too.
    Index near = kNoIndex;
    double near_max = u;
    tree.query(bi, [&] { return near_max; }, [&](Index t, double) {
      const Index j = live[static_cast<size_t>(t)];
      if (j == i) return;
      const double m = box_max_distance(bi, boxes.objects[static_cast<size_t>(j)]);
      if (m < near_max || (m == near_max && near != kNoIndex && j < near)) {
        near_max = m;
        near = j;
      }
    });
    u = std::min(u, near_max);
    if (near != kNoIndex && near != closest && near != cand[0] && near != cand[1] && near != cand[2])
      u = std::min(u, vertex_walk_bound(frame, boxes, i, near));

    // Up to kContactWalks more walks, to objects whose boxes overlap i's, until one proves
    // contact (each also bounds U_i).
    int walked = 0;
    tree.query(
        bi, [] { return 0.0; },
        [&](Index t, double) {
          const Index j = live[static_cast<size_t>(t)];
          if (u == 0 || walked >= kContactWalks || j == i || j == closest || j == near || j == cand[0] ||
              j == cand[1] || j == cand[2])
            return;
          ++walked;
          u = std::min(u, vertex_walk_bound(frame, boxes, i, j));
        },
        [&](std::int32_t) { return u == 0 || walked >= kContactWalks; });
    u *= 1 + kUpperBoundWidening;
    out.upper_bound[static_cast<size_t>(i)] = u;

    // Object-level PNS: the boxes within reach of i's.
    const double reach = u + slack;
    std::vector<std::pair<double, Index>> found;
    tree.query(bi, [&] { return reach; }, [&](Index t, double d2) {
      const Index j = live[static_cast<size_t>(t)];
      if (j != i) found.emplace_back(d2, j);
    });
    std::sort(found.begin(), found.end());
    auto& pns = out.pns[static_cast<size_t>(i)];
    pns.reserve(found.size());
    for (const auto& f : found) pns.push_back(f.second);
  });
  return out;
}

ObjectBoxTree ObjectBoxTree::build(const std::vector<AABB>& boxes, std::vector<Index> ids) {
  ObjectBoxTree tree;
  tree.ids = std::move(ids);
  std::vector<AABB> own;
  own.reserve(tree.ids.size());
  for (Index i : tree.ids) own.push_back(boxes[static_cast<size_t>(i)]);
  tree.bvh.build(own);
  return tree;
}

const ObjectBoxTree& FrameBoxes::object_tree() const {
  std::call_once(bvh_cache->object_once, [&] {
    std::vector<Index> ids;
    for (size_t i = 0; i < objects.size(); ++i)
      if (!objects[i].empty()) ids.push_back(static_cast<Index>(i));
    bvh_cache->object_tree = ObjectBoxTree::build(objects, std::move(ids));
  });
  return bvh_cache->object_tree;
}

std::vector<std::pair<Index, Index>> overlapping_box_pairs(const ObjectBoxTree& tree, const std::vector<AABB>& boxes,
                                                           int threads) {
  const std::vector<Index>& ids = tree.ids;
  std::vector<std::vector<Index>> partners(ids.size());
  parallel_for(ids.size(), threads, [&](size_t k) {
    const Index a = ids[k];
    tree.bvh.query_overlaps(boxes[static_cast<size_t>(a)], [](std::int32_t) { return false; }, [&](Index t) {
      const Index b = ids[static_cast<size_t>(t)];
      if (a < b) partners[k].push_back(b);
    });
  });
  std::vector<std::pair<Index, Index>> out;
  for (size_t k = 0; k < ids.size(); ++k)
    for (Index b : partners[k]) out.emplace_back(ids[k], b);
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace vproxq
