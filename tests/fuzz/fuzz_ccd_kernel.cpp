// Fuzzing the CCD kernel (core/geometry/ccd.hpp) for false negatives: each input decodes to a
// vertex–face or edge–edge query that touches at a known time t*, exactly. The 8 points lie
// on a small integer grid times a power of two (so coincident, collinear and coplanar points,
// degenerate triangles and edges, parallel and absent motion are common), t*, u and v are
// multiples of 1/16, and the vertex (or edge b) is moved so that at t* it meets the point of
// the triangle at (u, v) (of edge a at u). Every step of that construction is exact in
// double precision, so the primitives do touch at t*.
//
// What must hold, for the query and for its time reversal (start and end swapped, contact at
// 1 - t*): the kernel reports a collision no later than the contact; it decides it before the
// box limit (a limit hit is conservative, but such a query is a pathology worth knowing about:
// the first fuzzing run of the queries found one, ccd.cpp's excluded_within_triangle; without
// this check: -DVPROXQ_FUZZ_ALLOW_LIMIT); and at the reported TOI the primitives are within
// sqrt(3) ccd_max_tolerance() of each other (a hit certifies they are within δ_k on every
// axis: the pipeline's culling margins rely on it, as CcdKernel.AReportedToiIsATimeWhenThe-
// PrimitivesAreWithinTolerance checks on random queries).
#include "core/geometry/ccd.hpp"
#include "core/geometry/point_triangle.hpp"
#include "core/geometry/segment_segment.hpp"
#include "fuzz_support.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <utility>

using namespace vproxq;

namespace {

using Reader = fuzz::ByteReader;

using Points = std::array<Vec3, 4>;

void expect_found(bool vf, const Points& start, const Points& end, double contact) {
  const CcdResult r = vf ? vertex_face_ccd(start, end) : edge_edge_ccd(start, end);
  VPROXQ_FUZZ_CHECK(r.collides);
  VPROXQ_FUZZ_CHECK(r.toi <= contact);
#ifndef VPROXQ_FUZZ_ALLOW_LIMIT
  VPROXQ_FUZZ_CHECK(!r.hit_limit);
#endif
  if (r.hit_limit) return;
  Vec3 lo = start[0], hi = start[0];
  double magnitude = 0;
  for (const Points* p : {&start, &end})
    for (const Vec3& x : *p) {
      lo = lo.cwiseMin(x);
      hi = hi.cwiseMax(x);
      magnitude = std::max(magnitude, x.cwiseAbs().maxCoeff());
    }
  const double bound = std::sqrt(3.0) * ccd_max_tolerance((hi - lo).maxCoeff(), magnitude) * (1 + 1e-6);
  Points x;
  for (std::size_t i = 0; i < 4; ++i) x[i] = start[i] + r.toi * (end[i] - start[i]);
  const double d2 = vf ? point_triangle_distance(x[0], Triangle{x[1], x[2], x[3]}).squared_distance
                       : segment_segment_distance(x[0], x[1], x[2], x[3]).squared_distance;
  VPROXQ_FUZZ_CHECK(std::sqrt(d2) <= bound);
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in{data, size};
  const std::uint8_t head = in.next();
  const bool vf = (head & 1) == 0;
  // Coordinates: integers in [-8, 7] (most bytes) or [-128, 127], times 2^[-20, 20].
  const bool wide = (head & 2) != 0;
  const double unit = std::ldexp(1.0, in.next() % 41 - 20);
  Points start, end;
  for (Points* p : {&start, &end})
    for (Vec3& x : *p)
      for (int k = 0; k < 3; ++k) {
        const std::uint8_t b = in.next();
        x[k] = (wide ? static_cast<int>(b) - 128 : b % 16 - 8) * unit;
      }
  // t*, u, v in sixteenths; t* = 0 and 1 as often as any other.
  const double ts = (in.next() % 17) / 16.0;
  double u = (in.next() % 17) / 16.0, v = (in.next() % 17) / 16.0;
  if (vf && u + v > 1) {
    u = 1 - u;
    v = 1 - v;
  }
  auto at = [&](int i) {
    const auto k = static_cast<std::size_t>(i);
    return Vec3(start[k] + ts * (end[k] - start[k]));
  };
  // Exact: the differences are integers times the unit below 2^9, so every product by a
  // sixteenth and every sum has far fewer than 53 significant bits.
  const Vec3 shift = vf ? Vec3(at(1) + u * (at(2) - at(1)) + v * (at(3) - at(1)) - at(0))
                        : Vec3(at(0) + u * (at(1) - at(0)) - (at(2) + v * (at(3) - at(2))));
  for (int i = vf ? 0 : 2; i < (vf ? 1 : 4); ++i) {
    start[static_cast<std::size_t>(i)] += shift;
    end[static_cast<std::size_t>(i)] += shift;
  }
  expect_found(vf, start, end, ts);
  expect_found(vf, end, start, 1 - ts);
  return 0;
}
