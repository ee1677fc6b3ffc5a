// Differential fuzzing of the queries: each input decodes to a tiny two-frame scene (1-3
// objects of 3-8 vertices and 1-8 faces, coordinates mostly on a small integer grid times a
// power of two, so that shared, coplanar, collinear and repeated vertices are common, plus a
// few extreme values within the readers' range), and every query must equal its brute force
// bitwise, with the suite's comparisons (support/expect_same.hpp), without and with Stage II
// (CPU backends) at the decoded grid and thread count, as in
// tests/core/test_varied_scenes.cpp. Penetration depth, which has no brute force, must only
// not crash. CCD is compared only when no test stopped at the kernel's box limit (the one
// documented way in which culling may differ from the brute force, core/query/ccd.hpp).
#include "core/query/ccd.hpp"
#include "core/query/inter_distance.hpp"
#include "core/query/intersecting_pairs.hpp"
#include "core/query/intra_distance.hpp"
#include "core/query/penetration_depth.hpp"
#include "core/voronoi/ccd_stage2.hpp"
#include "core/voronoi/self_stage2.hpp"
#include "core/voronoi/stage2.hpp"
#include "fuzz_support.hpp"
#include "support/expect_same.hpp"
#include "trap_on_test_failure.hpp"

#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

using namespace vproxq;

namespace {

using Reader = fuzz::ByteReader;

double coordinate(Reader& in, double unit) {
  const std::uint8_t b = in.next();
  if (b < 240) return (b % 16 - 8) * unit;
  switch (b) {
    // The extremes stay in the coordinate range the readers accept (0, or 2^-200 <= |x| <
    // 2^200: io/read_util.cpp), for which the exact predicates are exact; 1e-300 beside 1e-7
    // is outside it (products of their differences underflow) and the readers reject it.
    case 240: return 0x1p-200;
    case 241: return -0x1p-200;
    case 242: return 0x1p-199 * 3;
    case 243: return 1e15 * unit;
    case 244: return -1e15 * unit;
    case 245: return 0.1 * unit;
    case 246: return std::nextafter(unit, 2 * unit);
    case 247: return unit / 3;
    default: return (b - 248) * 0.5 * unit;
  }
}

}  // namespace

// The comparisons are the test suite's (support/expect_same.hpp); a failed one stops the
// fuzzer, which records the input.
extern "C" int LLVMFuzzerInitialize(int*, char***) {
  fuzz::trap_on_test_failure();
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  Reader in{data, size};
  const int objects = 1 + in.next() % 3;
  const int grid = 1 + in.next() % 40;
  const int threads = 1 + in.next() % 2;
  const double unit = std::ldexp(in.next() & 1 ? 1.0 : 0.1, in.next() % 41 - 20);
  Frame from, to;
  from.index = 0;
  to.index = 1;
  for (int o = 0; o < objects; ++o) {
    auto topology = std::make_shared<Topology>();
    topology->num_vertices = 3 + in.next() % 6;
    const int faces = 1 + in.next() % 8;
    for (int f = 0; f < faces; ++f) {
      Face face;
      for (Index& v : face) v = in.next() % topology->num_vertices;
      topology->faces.push_back(face);
    }
    Object a;
    a.name = "o" + std::to_string(o);
    a.topology = topology;
    for (Index v = 0; v < topology->num_vertices; ++v) {
      const double x = coordinate(in, unit), y = coordinate(in, unit), z = coordinate(in, unit);
      a.positions.emplace_back(x, y, z);
    }
    Object b = a;  // at t = 1, each vertex stays or moves to a decoded position
    for (Vec3& p : b.positions)
      if (in.next() & 1) {
        const double x = coordinate(in, unit), y = coordinate(in, unit), z = coordinate(in, unit);
        p = Vec3(x, y, z);
      }
    from.objects.push_back(a);
    to.objects.push_back(b);
  }

  static std::unique_ptr<DiscreteVoronoiBackend> inter_backends[2] = {make_cpu_voronoi_backend(1),
                                                                       make_cpu_voronoi_backend(2)};
  static std::unique_ptr<SelfVoronoiBackend> self_backends[2] = {make_cpu_self_voronoi_backend(1),
                                                                  make_cpu_self_voronoi_backend(2)};
  const FrameBoxes boxes = FrameBoxes::compute(from, threads);
  const ObjectBroadPhase stage1 = object_broad_phase(from, boxes, threads);

  const auto inter_ref = inter_object_distance_brute_force(from);
  const VoronoiBounds vb = compute_voronoi_bounds(from, boxes, stage1, *inter_backends[threads - 1], grid, threads);
  for (const VoronoiBounds* v : {static_cast<const VoronoiBounds*>(nullptr), &vb}) {
    const auto got = inter_object_distance(from, boxes, stage1, InterDistanceOptions{threads, v});
    test::expect_same_inter(got, inter_ref, v ? "inter cpu" : "inter off");
  }

  const auto intra_ref = intra_object_distance_brute_force(from);
  const auto ring2 = ring2_upper_bounds(from, threads);
  const SelfVoronoiBounds sb = compute_self_voronoi_bounds(from, boxes, ring2, *self_backends[threads - 1], grid, threads);
  for (const SelfVoronoiBounds* v : {static_cast<const SelfVoronoiBounds*>(nullptr), &sb}) {
    const auto got = intra_object_distance(from, boxes, ring2, IntraDistanceOptions{threads, v});
    test::expect_same_intra(got, intra_ref, v ? "intra cpu" : "intra off");
  }

  const auto pairs_ref = intersecting_pairs_brute_force(from);
  std::vector<double> object_distance;
  for (const auto& d : inter_ref.per_object) object_distance.push_back(d.distance);
  for (const VoronoiBounds* v : {static_cast<const VoronoiBounds*>(nullptr), &vb}) {
    IntersectingPairsOptions opts;
    opts.threads = threads;
    opts.voronoi = v;
    VPROXQ_FUZZ_CHECK(intersecting_pairs(from, boxes, opts).pairs == pairs_ref.pairs);
    opts.object_distance = &object_distance;  // as the run passes them
    VPROXQ_FUZZ_CHECK(intersecting_pairs(from, boxes, opts).pairs == pairs_ref.pairs);
  }
  PenetrationDepthOptions pd;
  pd.threads = threads;
  (void)penetration_depth(from, boxes, pairs_ref.pairs, pd);

  const CcdStepResult ref = continuous_collisions_brute_force(from, to);
  const CcdSweep sweep = CcdSweep::compute(from, to, threads);
  const CcdVoxelCulling voxels(from, to, sweep, grid, threads);
  for (const CcdVoxelCulling* v : {static_cast<const CcdVoxelCulling*>(nullptr), &voxels}) {
    const CcdStepResult got = continuous_collisions(from, to, sweep, CcdOptions{threads, v});
    if (ref.counters.limit_hits > 0 || got.counters.limit_hits > 0) continue;
    test::expect_same_ccd(got, ref);
  }
  return 0;
}
