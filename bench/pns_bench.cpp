// vproxq-bench-pns: how many exact triangle-pair tests the distance queries need, frame by
// frame, counted four ways for the inter-object and the intra-object (self) distance, with
// and without Stage II (the CPU backend; it makes the same culling decisions as the GL one).
//
//   vproxq-bench-pns bench-out/blobs-200/scene.json --grid 64 --threads 2 [--frames 0:5]
//                    [--json out.json]
//
// Per frame and query (inter: every object's nearest other object; intra: every triangle's
// nearest non-adjacent triangle of its own object):
//   tests     exact tests that vproxq's Stage III ran, AABB-only (off) and with Stage II (cpu):
//             a nearest-first search whose bound shrinks to the best distance found so far,
//             and which skips pairs whose separating-axis bound exceeds it.
//   floor     pairs that no search pruning by triangle boxes can skip: those whose boxes lie
//             within the final answer (off), and, with Stage II, of them those where both
//             triangles' D_l are within it too (cpu). Stage III gets below these through the
//             separating-axis bound (core/geometry/separation_bound.hpp), ties, and, intra,
//             because it evaluates a pair once for both triangles while the floor counts
//             (f, g) and (g, f) apart.
//   fixed     the feature-level PNS of the paper (5.2.1) with its fixed bounds: every pair
//             whose boxes lie within the object's (or, for intra, the triangle's) upper bound,
//             the bound being Stage I's U_i (inter) or the 2-ring bound (intra) without Stage
//             II, and D_u with Stage II, which also culls the triangles whose D_l exceeds it.
//             This is what the paper's figure 13 counts: exact tests of a Stage III that tests
//             the whole PNS.
// All counts include the rounding slack vproxq adds to every bound (rounding_slack()), as
// Stage III does. The answers of the off and cpu runs are compared (they must be identical).
#include "app/allocator.hpp"
#include "bench/bench_common.hpp"
#include "core/broad_phase/object_broad_phase.hpp"
#include "core/broad_phase/triangle_bvh.hpp"
#include "core/mesh/adjacency.hpp"
#include "core/parallel.hpp"
#include "core/query/inter_distance.hpp"
#include "core/query/intra_distance.hpp"
#include "core/voronoi/self_stage2.hpp"
#include "core/voronoi/stage2.hpp"
#include "io/scene_source.hpp"

#include <CLI/CLI.hpp>

#include <array>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

namespace {

using vproxq::Index;
using Count = std::uint64_t;

/// The four counts of one query on one frame (see the header comment).
struct Counts {
  Count tests_off = 0, tests_cpu = 0;
  Count floor_off = 0, floor_cpu = 0;
  Count fixed_off = 0, fixed_cpu = 0;

  std::array<Count*, 6> fields() {
    return {&tests_off, &tests_cpu, &floor_off, &floor_cpu, &fixed_off, &fixed_cpu};
  }
  Counts& operator+=(Counts c) {
    const auto mine = fields(), theirs = c.fields();
    for (std::size_t k = 0; k < mine.size(); ++k) *mine[k] += *theirs[k];
    return *this;
  }
};

struct FrameRow {
  std::size_t frame = 0;
  long long triangles = 0;
  Counts inter, intra;
  bool identical = true;
};

struct Options {
  std::string scene;
  int threads = 2;
  int grid = 0;  ///< 0: vproxq's default
  std::string frames;
  std::string json;
};

/// Sums count(i) over i in [0, n) on `threads` threads.
template <typename F>
Count parallel_sum(std::size_t n, int threads, const F& count) {
  std::atomic<Count> total{0};
  vproxq::parallel_for(n, threads, [&](std::size_t i) { total += count(i); });
  return total.load();
}

/// D_l of a triangle, or -inf (cannot cull) without Stage II.
double lower_of(const std::vector<std::vector<double>>* lower, std::size_t object, Index t) {
  return lower ? (*lower)[object][static_cast<std::size_t>(t)] : -vproxq::kInfinity;
}

/// Inter-object: pairs (f in i, g in j != i) whose boxes lie within bound(i), f and g both with
/// D_l within it; the objects j are those whose box lies within it.
template <typename Bound>
Count count_inter_pairs(const vproxq::Frame& frame, const vproxq::FrameBoxes& boxes,
                        const std::vector<vproxq::TriangleBvh>& bvhs,
                        const std::vector<std::vector<double>>* lower, int threads,
                        const Bound& bound) {
  const std::size_t n = frame.objects.size();
  return parallel_sum(n, threads, [&](std::size_t i) {
    const double b = bound(i);
    Count c = 0;
    for (std::size_t j = 0; j < n; ++j) {
      if (j == i || vproxq::box_distance_squared(boxes.objects[i], boxes.objects[j]) > b * b)
        continue;
      const auto& tb = boxes.triangles[i];
      for (Index f = 0; f < static_cast<Index>(tb.size()); ++f) {
        if (lower_of(lower, i, f) > b) continue;
        bvhs[j].query(tb[static_cast<std::size_t>(f)], [b] { return b; }, [&](Index g, double) {
          if (lower_of(lower, j, g) <= b) ++c;
        });
      }
    }
    return c;
  });
}

/// Intra-object: per triangle f, the non-adjacent g of its object whose box lies within
/// bound(i, f) and whose D_l is within it.
template <typename Bound>
Count count_intra_pairs(const vproxq::Frame& frame, const vproxq::FrameBoxes& boxes,
                        const std::vector<vproxq::TriangleBvh>& bvhs,
                        const std::vector<std::vector<double>>* lower, int threads,
                        const Bound& bound) {
  Count total = 0;
  for (std::size_t i = 0; i < frame.objects.size(); ++i) {
    const vproxq::Object& o = frame.objects[i];
    const auto& faces = o.topology->faces;
    const auto& tb = boxes.triangles[i];
    total += parallel_sum(tb.size(), threads, [&](std::size_t uf) {
      const Index f = static_cast<Index>(uf);
      const double b = bound(i, uf);
      Count c = 0;
      bvhs[i].query(tb[uf], [b] { return b; }, [&](Index g, double) {
        if (g == f || vproxq::Adjacency::share_vertex(faces[uf], faces[static_cast<std::size_t>(g)]))
          return;
        if (lower_of(lower, i, g) <= b) ++c;
      });
      return c;
    });
  }
  return total;
}

FrameRow measure(const vproxq::Frame& frame, std::size_t k, const Options& opt) {
  FrameRow row;
  row.frame = k;
  const int threads = opt.threads;
  const std::size_t n = frame.objects.size();
  for (const auto& o : frame.objects) row.triangles += o.num_triangles();

  const vproxq::FrameBoxes boxes = vproxq::FrameBoxes::compute(frame, threads);
  const vproxq::ObjectBroadPhase stage1 = vproxq::object_broad_phase(frame, boxes, threads);
  const auto ring2 = vproxq::ring2_upper_bounds(frame, threads);
  const double slack = vproxq::rounding_slack(boxes.magnitude);
  std::vector<vproxq::TriangleBvh> bvhs(n);
  vproxq::parallel_for(n, threads, [&](std::size_t i) { bvhs[i].build(boxes.triangles[i]); });

  const auto backend = vproxq::make_cpu_voronoi_backend(threads);
  const vproxq::VoronoiBounds vb =
      vproxq::compute_voronoi_bounds(frame, boxes, stage1, *backend, opt.grid, threads);
  const auto self_backend = vproxq::make_cpu_self_voronoi_backend(threads);
  const vproxq::SelfVoronoiBounds svb =
      vproxq::compute_self_voronoi_bounds(frame, boxes, ring2, *self_backend, opt.grid, threads);

  // The queries themselves, AABB-only and with Stage II.
  vproxq::InterDistanceOptions inter_opt;
  inter_opt.threads = threads;
  const auto inter_off = vproxq::inter_object_distance(frame, boxes, stage1, inter_opt);
  inter_opt.voronoi = &vb;
  const auto inter_cpu = vproxq::inter_object_distance(frame, boxes, stage1, inter_opt);
  vproxq::IntraDistanceOptions intra_opt;
  intra_opt.threads = threads;
  const auto intra_off = vproxq::intra_object_distance(frame, boxes, ring2, intra_opt);
  intra_opt.voronoi = &svb;
  const auto intra_cpu = vproxq::intra_object_distance(frame, boxes, ring2, intra_opt);
  row.inter.tests_off = inter_off.counters.exact_tests;
  row.inter.tests_cpu = inter_cpu.counters.exact_tests;
  row.intra.tests_off = intra_off.counters.intra_exact_tests;
  row.intra.tests_cpu = intra_cpu.counters.intra_exact_tests;
  for (std::size_t i = 0; i < n; ++i) {
    const auto& a = inter_off.per_object[i];
    const auto& b = inter_cpu.per_object[i];
    row.identical = row.identical && a.distance == b.distance && a.triangles == b.triangles &&
                    a.nearest_object == b.nearest_object;
    const auto& ta = intra_off.per_object[i].per_triangle;
    const auto& tb = intra_cpu.per_object[i].per_triangle;
    for (std::size_t t = 0; t < ta.size(); ++t)
      row.identical = row.identical && ta[t].distance == tb[t].distance && ta[t].nearest == tb[t].nearest;
  }

  // Inter-object counts. An object without a nearest object (alone) has bound -inf: nothing.
  auto answer = [&](std::size_t i) {
    const double d = inter_off.per_object[i].distance;
    return d == vproxq::kInfinity ? -vproxq::kInfinity : d + slack;
  };
  row.inter.floor_off = count_inter_pairs(frame, boxes, bvhs, nullptr, threads, answer);
  row.inter.floor_cpu = count_inter_pairs(frame, boxes, bvhs, &vb.triangle_lower, threads, answer);
  row.inter.fixed_off = count_inter_pairs(frame, boxes, bvhs, nullptr, threads, [&](std::size_t i) {
    return stage1.upper_bound[i] + slack;
  });
  row.inter.fixed_cpu = count_inter_pairs(frame, boxes, bvhs, &vb.triangle_lower, threads,
                                          [&](std::size_t i) { return vb.object_upper[i] + slack; });

  // Intra-object counts.
  auto triangle_answer = [&](std::size_t i, std::size_t f) {
    const double d = intra_off.per_object[i].per_triangle[f].distance;
    return d == vproxq::kInfinity ? -vproxq::kInfinity : d + slack;
  };
  row.intra.floor_off = count_intra_pairs(frame, boxes, bvhs, nullptr, threads, triangle_answer);
  row.intra.floor_cpu =
      count_intra_pairs(frame, boxes, bvhs, &svb.triangle_lower, threads, triangle_answer);
  row.intra.fixed_off = count_intra_pairs(frame, boxes, bvhs, nullptr, threads,
                                          [&](std::size_t i, std::size_t f) { return ring2[i][f] + slack; });
  row.intra.fixed_cpu = count_intra_pairs(
      frame, boxes, bvhs, &svb.triangle_lower, threads, [&](std::size_t i, std::size_t f) {
        return std::min(ring2[i][f], svb.triangle_upper[i][f]) + slack;
      });
  return row;
}

double ratio(Count a, Count b) { return b == 0 ? 0.0 : static_cast<double>(a) / static_cast<double>(b); }

void print_row(const char* label, const Counts& c) {
  std::printf("%8s %12llu %12llu %7.2f %12llu %12llu %7.2f %14llu %12llu %8.1f\n", label,
              static_cast<unsigned long long>(c.tests_off), static_cast<unsigned long long>(c.tests_cpu),
              ratio(c.tests_off, c.tests_cpu), static_cast<unsigned long long>(c.floor_off),
              static_cast<unsigned long long>(c.floor_cpu), ratio(c.floor_off, c.floor_cpu),
              static_cast<unsigned long long>(c.fixed_off), static_cast<unsigned long long>(c.fixed_cpu),
              ratio(c.fixed_off, c.fixed_cpu));
}

std::string counts_json(const Counts& c) {
  char line[512];
  std::snprintf(line, sizeof line,
                "{\"tests_off\": %llu, \"tests_cpu\": %llu, \"floor_off\": %llu, "
                "\"floor_cpu\": %llu, \"fixed_off\": %llu, \"fixed_cpu\": %llu}",
                static_cast<unsigned long long>(c.tests_off), static_cast<unsigned long long>(c.tests_cpu),
                static_cast<unsigned long long>(c.floor_off), static_cast<unsigned long long>(c.floor_cpu),
                static_cast<unsigned long long>(c.fixed_off), static_cast<unsigned long long>(c.fixed_cpu));
  return line;
}

int run(const Options& opt) {
  const vproxq::SceneSource scene = vproxq::SceneSource::open(opt.scene);
  const auto [first, last] = vproxq::bench::frame_range(opt.frames, scene.frame_count());
  std::printf("scene %s (%s): frames %zu..%zu of %zu; grid %s; threads %d\n", opt.scene.c_str(),
              scene.name().c_str(), first, last - 1, scene.frame_count(),
              opt.grid > 0 ? std::to_string(opt.grid).c_str() : "default", opt.threads);
  std::printf("%8s %12s %12s %7s %12s %12s %7s %14s %12s %8s\n", "query", "tests off",
              "tests cpu", "ratio", "floor off", "floor cpu", "ratio", "fixed off", "fixed cpu",
              "ratio");
  std::vector<FrameRow> rows;
  Counts sum_inter, sum_intra;
  bool identical = true;
  for (std::size_t k = first; k < last; ++k) {
    const FrameRow row = measure(scene.load_frame(k), k, opt);
    std::printf("frame %zu (%lld triangles)%s\n", k, row.triangles,
                row.identical ? "" : ": OFF AND CPU ANSWERS DIFFER");
    print_row("inter", row.inter);
    print_row("intra", row.intra);
    sum_inter += row.inter;
    sum_intra += row.intra;
    identical = identical && row.identical;
    rows.push_back(row);
  }
  std::printf("all frames\n");
  print_row("inter", sum_inter);
  print_row("intra", sum_intra);
  std::printf("ratio = off / cpu. tests: Stage III's exact tests (running-best search with the "
              "separating-axis bound); floor: "
              "pairs within the final answer that box (and D_l) culling cannot skip; fixed: the "
              "paper's feature-level PNS with fixed bounds (U_i or the 2-ring bound; D_u and "
              "D_l with Stage II).\n");

  if (!opt.json.empty()) {
    std::string text = "{\n  \"tool\": \"vproxq-bench-pns\",\n  \"grid\": " +
                       std::to_string(opt.grid) + ",\n  \"frames\": [";
    for (std::size_t r = 0; r < rows.size(); ++r)
      text += std::string(r ? "," : "") + "\n    {\"frame\": " + std::to_string(rows[r].frame) +
              ", \"identical\": " + (rows[r].identical ? "true" : "false") +
              ", \"inter\": " + counts_json(rows[r].inter) +
              ", \"intra\": " + counts_json(rows[r].intra) + "}";
    text += "\n  ]\n}\n";
    vproxq::bench::write_file_atomically(opt.json, text);
  }
  if (!identical) {
    std::printf("the answers with and without Stage II differ on some frame\n");
    return 1;
  }
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  vproxq::keep_freed_memory_for_reuse();  // as vproxq does
  CLI::App app{"vproxq-bench-pns: counts the exact tests of the inter- and intra-object distance "
               "with and without Stage II, against their floors and the paper's fixed-bound PNS."};
  Options opt;
  app.add_option("scene", opt.scene, "scene.json or mesh file")->required();
  app.add_option("--threads", opt.threads, "worker threads")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  app.add_option("--grid", opt.grid, "Stage II grid (cells along the longest axis); 0: default")
      ->check(CLI::Range(0, 4096))
      ->capture_default_str();
  app.add_option("--frames", opt.frames, "frames A:B (A..B-1; A: and :B also work), default all");
  app.add_option("--json", opt.json, "also write the per-frame counts to this JSON file");
  return vproxq::bench::guarded_main("vproxq-bench-pns", app, argc, argv, [&] { return run(opt); });
}
