// Differential fuzzing of the penetration depth: each input decodes to two closed,
// consistently oriented objects (a tetrahedron, an octahedron, or a box of 1 or 2 cells per
// axis; outward or inward; the 2-cell box sometimes with a well pushed into its top, through
// its bottom at the deepest; sometimes halved; vertices jittered on a small grid times a power
// of two, sometimes by a third, sometimes far from the origin) placed so that they often
// overlap. Checked, against brute forces that share no search code with penetration_depth():
//  - 1 and 2 threads give the same entries, every field;
//  - every entry between the two objects (status ok or too_deep) lists as inside vertices
//    exactly the walk closure of the brute-force winding number (tests/support/pd_checks.hpp),
//    and is too_deep exactly where a connected set of them has no outside neighbour; with
//    status ok: a unit direction, a depth no narrower than the inside vertices' extent
//    along it, and the deepest vertex and its nearest point of the exact max-min over every
//    face (the tie rules of docs/algorithms.md); no deepest vertex only when no vertex is inside;
//  - the twin (docs/algorithms.md, "Self-intersections": for two objects merged into one, the inside test
//    is exactly the inter-object one at every vertex whose star does not pass through itself;
//    such a vertex is not exempted here, so a jittered shape with one inside would show as a
//    difference): where neither object intersects itself and their
//    intersecting pairs form one contact, the two merged into one object (b's ids after a's)
//    have the same intersecting pairs, and, unless the self entry says self_intersection
//    (the sheets' local orientation undecidable, e.g. coplanar covers), the same status and
//    inside vertices; for too_deep the same overlapping triangles, for ok the same deepest
//    vertex, depth and direction (up to its sign).
#include "core/query/intersecting_pairs.hpp"
#include "core/query/penetration_depth.hpp"
#include "fuzz_support.hpp"
#include "support/pd_checks.hpp"
#include "support/self_meshes.hpp"
#include "trap_on_test_failure.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <numeric>
#include <string>
#include <vector>

using namespace vproxq;

namespace {

using Reader = fuzz::ByteReader;

/// A convex base shape 4 units across near the origin, faces oriented outwards.
Object base_shape(int kind) {
  std::vector<Vec3> p;
  std::vector<Face> f;
  if (kind == 0) {  // tetrahedron
    p = {{-2, -2, -2}, {2, -2, -2}, {-2, 2, -2}, {-2, -2, 2}};
    f = {{0, 1, 2}, {0, 1, 3}, {0, 2, 3}, {1, 2, 3}};
  } else if (kind == 1) {  // octahedron
    p = {{2, 0, 0}, {-2, 0, 0}, {0, 2, 0}, {0, -2, 0}, {0, 0, 2}, {0, 0, -2}};
    for (Index x : {0, 1})
      for (Index y : {2, 3})
        for (Index z : {4, 5}) f.push_back({x, y, z});
  } else {  // box with n cells per axis, two triangles per cell of each face
    const int n = kind == 2 ? 1 : 2;
    auto id = [&](int i, int j, int k) {
      const Vec3 q(-2 + 4.0 * i / n, -2 + 4.0 * j / n, -2 + 4.0 * k / n);
      const auto it = std::find(p.begin(), p.end(), q);
      if (it != p.end()) return static_cast<Index>(it - p.begin());
      p.push_back(q);
      return static_cast<Index>(p.size() - 1);
    };
    for (int axis = 0; axis < 3; ++axis)
      for (int side : {0, n})
        for (int u = 0; u < n; ++u)
          for (int v = 0; v < n; ++v) {
            auto corner = [&](int du, int dv) {
              int g[3];
              g[axis] = side;
              g[(axis + 1) % 3] = u + du;
              g[(axis + 2) % 3] = v + dv;
              return id(g[0], g[1], g[2]);
            };
            f.push_back({corner(0, 0), corner(1, 0), corner(1, 1)});
            f.push_back({corner(0, 0), corner(1, 1), corner(0, 1)});
          }
  }
  Vec3 centroid = Vec3::Zero();
  for (const Vec3& q : p) centroid += q / static_cast<double>(p.size());
  for (Face& face : f) {  // outwards: the normal points away from the centroid (convex)
    const Vec3& a = p[static_cast<size_t>(face[0])];
    const Vec3 n = (p[static_cast<size_t>(face[1])] - a).cross(p[static_cast<size_t>(face[2])] - a);
    if (n.dot(a - centroid) < 0) std::swap(face[1], face[2]);
  }
  return test::make_object(p, f, "");
}

double jitter(Reader& in) {
  const std::uint8_t b = in.next();
  if (b < 200) return b % 5 * 0.5 - 1;  // -1 .. 1 in halves
  if (b < 250) return (b % 3 - 1) / 3.0;
  return std::ldexp(b & 1 ? 1.0 : -1.0, -20);
}

/// Changes to an object's base shape, from the byte after both objects (0 past the end of
/// the input, so an input that ends with the objects decodes as before): the 2-cell box's top
/// centre pushed down 1, 2, 3 or 4.5 (a well; at 4.5 through the bottom, so the box
/// intersects itself), and the whole shape halved (small enough to sit in another's well:
/// a too_deep case).
struct Variant {
  int dent = 0;  ///< 0: none, 1..4: the depths above
  bool half = false;
};

Object decode_object(Reader& in, double unit, double offset, const std::array<int, 3>& salt, const std::string& name,
                     const Variant& variant = {}) {
  const std::uint8_t flags = in.next();
  Object o = base_shape(flags % 4);
  o.name = name;
  if (variant.dent > 0 && flags % 4 == 3) {
    constexpr double kDents[] = {1, 2, 3, 4.5};
    for (Vec3& p : o.positions)
      if (p == Vec3(0, 0, 2)) p.z() -= kDents[variant.dent - 1];
  }
  if (variant.half)
    for (Vec3& p : o.positions) p *= 0.5;
  if (flags & 4) {  // inward
    auto topo = std::make_shared<Topology>(*o.topology);
    for (Face& face : topo->faces) std::swap(face[1], face[2]);
    o.topology = topo;
  }
  Vec3 shift;
  for (int a = 0; a < 3; ++a) shift[a] = ((in.next() + salt[static_cast<size_t>(a)]) % 17 - 8) * 0.5;
  for (Vec3& p : o.positions) {
    Vec3 q = p + shift;
    if (in.next() & 1)
      for (int a = 0; a < 3; ++a) q[a] += jitter(in);
    for (int a = 0; a < 3; ++a) q[a] = q[a] * unit + offset;
    p = q;
  }
  return o;
}

Frame frame_of(std::vector<Object> objects) {
  Frame frame;
  frame.objects = std::move(objects);
  return frame;
}

std::vector<PenetrationDepth> run_pd(const Frame& frame, const std::vector<IntersectingPair>& pairs, int threads) {
  const FrameBoxes boxes = FrameBoxes::compute(frame, threads);
  return penetration_depth(frame, boxes, pairs, PenetrationDepthOptions{threads}).pairs;
}

/// Number of contacts of the pairs (docs/algorithms.md: pairs linked by a shared triangle or by triangles
/// sharing a vertex), each pair's triangles as given by `faces_of`.
template <class Faces>
size_t count_contacts(const std::vector<IntersectingPair>& pairs, Faces faces_of) {
  std::vector<size_t> parent(pairs.size());
  std::iota(parent.begin(), parent.end(), size_t{0});
  auto find = [&](size_t x) {
    while (parent[x] != x) x = parent[x] = parent[parent[x]];
    return x;
  };
  for (size_t i = 0; i < pairs.size(); ++i)
    for (size_t j = i + 1; j < pairs.size(); ++j) {
      bool linked = false;
      for (const Face& fi : faces_of(pairs[i]))
        for (const Face& fj : faces_of(pairs[j]))
          for (Index u : fi)
            for (Index w : fj) linked = linked || u == w;
      if (linked) parent[find(i)] = find(j);
    }
  size_t roots = 0;
  for (size_t i = 0; i < pairs.size(); ++i) roots += find(i) == i;
  return roots;
}

std::vector<Index> sorted_union(const std::vector<Index>& a, const std::vector<Index>& b, Index shift) {
  std::vector<Index> out = a;
  for (Index v : b) out.push_back(v + shift);
  std::sort(out.begin(), out.end());
  return out;
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::trap_on_test_failure();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in{data, size};
  const std::uint8_t scale = in.next();
  const double unit = std::ldexp(1.0, scale % 21 - 10);
  const double offset = scale >= 224 ? std::ldexp(1.0, 20) * unit * 3 : 0.0;
  (void)decode_object(in, unit, offset, {8, 8, 8}, "a");
  (void)decode_object(in, unit, offset, {11, 10, 9}, "b");
  const std::uint8_t bits = in.next();
  in = Reader{data, size};  // decode again, with the variant read after both
  (void)in.next();
  auto dent = [](int three_bits) { return three_bits >= 4 ? three_bits - 3 : 0; };
  const Object a = decode_object(in, unit, offset, {8, 8, 8}, "a", {dent(bits & 7), (bits & 64) != 0});
  const Object b = decode_object(in, unit, offset, {11, 10, 9}, "b", {dent(bits >> 3 & 7), (bits & 128) != 0});
  const Frame frame = frame_of({a, b});
  const std::vector<IntersectingPair> pairs = intersecting_pairs_brute_force(frame).pairs;

  const auto pd = run_pd(frame, pairs, 1);
  test::expect_same_pd(pd, run_pd(frame, pairs, 2), "threads 1 vs 2");

  double magnitude = 0;
  for (const Object& o : frame.objects)
    for (const Vec3& p : o.positions) magnitude = std::max(magnitude, p.cwiseAbs().maxCoeff());
  const double tolerance = 0x1p-40 * magnitude;
  const PenetrationDepth* inter = nullptr;
  for (const PenetrationDepth& e : pd) {
    test::expect_reason_holds(frame, e, pairs);
    if (e.objects[0] == e.objects[1]) continue;  // a jittered object intersecting itself: no crash, same for all threads
    inter = &e;
    if (e.status != PdStatus::Ok && e.status != PdStatus::TooDeep) continue;
    (void)test::expect_inside_is_walk_closure(frame, e, pairs);
    EXPECT_EQ(e.status == PdStatus::TooDeep, test::has_swallowed_set(frame, e)) << pd_status_name(e.status);
    if (e.status != PdStatus::Ok) continue;
    EXPECT_TRUE(std::isfinite(e.depth) && e.depth >= 0) << e.depth;
    EXPECT_NEAR(e.direction.norm(), 1.0, 1e-12);
    double lo = kInfinity, hi = -kInfinity;
    for (int side = 0; side < 2; ++side)
      for (Index v : e.inside_vertices[static_cast<size_t>(side)]) {
        const double x = frame.objects[static_cast<size_t>(e.objects[static_cast<size_t>(side)])].positions[static_cast<size_t>(v)].dot(e.direction);
        lo = std::min(lo, x);
        hi = std::max(hi, x);
      }
    if (lo <= hi) {
      EXPECT_GE(e.depth, hi - lo - tolerance);
    }
    if (e.inside_vertices[0].empty() && e.inside_vertices[1].empty()) {
      EXPECT_EQ(e.deepest_vertex, kNoIndex);
      continue;
    }
    const test::ExactDeepest expected = test::exact_deepest(frame, e);
    if (e.deepest_vertex == kNoIndex) {  // only where the deepest vertex's nearest point is computed on it
      EXPECT_EQ(expected.nearest, frame.objects[static_cast<size_t>(expected.object)].positions[static_cast<size_t>(expected.vertex)]);
      continue;
    }
    EXPECT_EQ(e.deepest_object, expected.object);
    EXPECT_EQ(e.deepest_vertex, expected.vertex);
    EXPECT_EQ(e.nearest_point, expected.nearest);
  }

  // The twin: a and b as one object of two components.
  if (!inter || (inter->status != PdStatus::Ok && inter->status != PdStatus::TooDeep)) return 0;
  for (const IntersectingPair& p : pairs)
    if (p.object_a == p.object_b) return 0;  // an object intersects itself
  const auto faces_of = [&](const IntersectingPair& p) {
    return std::array<Face, 2>{a.topology->faces[static_cast<size_t>(p.tri_a)], b.topology->faces[static_cast<size_t>(p.tri_b)]};
  };
  if (count_contacts(pairs, faces_of) != 1) return 0;
  const Index nv = a.num_vertices(), nt = a.num_triangles();
  std::vector<Vec3> positions = a.positions;
  positions.insert(positions.end(), b.positions.begin(), b.positions.end());
  std::vector<Face> faces = a.topology->faces;
  for (const Face& f : b.topology->faces) faces.push_back({f[0] + nv, f[1] + nv, f[2] + nv});
  const Frame one = frame_of({test::make_object(positions, faces, "ab")});
  const std::vector<IntersectingPair> self_pairs = intersecting_pairs_brute_force(one).pairs;
  std::vector<IntersectingPair> shifted;
  for (const IntersectingPair& p : pairs) shifted.push_back({0, p.tri_a, 0, p.tri_b + nt});
  EXPECT_EQ(self_pairs, shifted);
  const auto self = run_pd(one, self_pairs, 1);
  test::expect_same_pd(self, run_pd(one, self_pairs, 2), "self, threads 1 vs 2");
  EXPECT_EQ(self.size(), 1u);
  for (const PenetrationDepth& e : self) test::expect_reason_holds(one, e, self_pairs);
  if (self.size() != 1 || self[0].status == PdStatus::SelfIntersection) return 0;
  const PenetrationDepth& s = self[0];
  EXPECT_EQ(s.status, inter->status) << pd_status_name(s.status) << " vs " << pd_status_name(inter->status);
  EXPECT_EQ(sorted_union(s.inside_vertices[0], s.inside_vertices[1], 0),
            sorted_union(inter->inside_vertices[0], inter->inside_vertices[1], nv));
  if (inter->status == PdStatus::TooDeep) {  // the walk's vertices and step 2's triangles, as one list
    EXPECT_EQ(sorted_union(s.overlapping_triangles[0], s.overlapping_triangles[1], 0),
              sorted_union(inter->overlapping_triangles[0], inter->overlapping_triangles[1], nt));
  }
  if (s.status != PdStatus::Ok || inter->status != PdStatus::Ok) return 0;
  const Index twin_vertex = inter->deepest_vertex == kNoIndex ? kNoIndex
                            : inter->deepest_object == 0   ? inter->deepest_vertex
                                                           : inter->deepest_vertex + nv;
  EXPECT_EQ(s.deepest_vertex, twin_vertex);
  EXPECT_LE(std::abs(s.depth - inter->depth), tolerance) << s.depth << " vs " << inter->depth;
  // A face normal (no deepest vertex) is the first of the equally narrow ones, objects[0]'s
  // faces first; for the self entry, side 0 is the deepest vertex's piece of sheet, which is
  // b's where the deepest vertex was b's but gave no direction (its nearest point computed
  // on it): the order of the sides, and so the choice among ties, can differ then.
  const bool sides_differ = s.deepest_vertex == kNoIndex && !s.inside_vertices[0].empty() &&
                            s.inside_vertices[0].front() >= nv;
  if (!sides_differ) {
    EXPECT_NEAR(std::abs(s.direction.dot(inter->direction)), 1.0, 1e-12);
  }
  return 0;
}
