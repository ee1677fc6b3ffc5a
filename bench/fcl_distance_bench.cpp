// vproxq-bench-fcl: per-frame inter-object distance (every object's nearest other object and
// the separation distance), vproxq against FCL 0.7, on the frames of a scene.
//
//   vproxq-bench-fcl bench-out/scene.json --threads 2 --frames 0:5 --repeat 3 [--json out.json]
//
// For each frame, with the frame already loaded (loading is not timed):
//   vproxq  per backend of --voronoi (default off): the triangle and object boxes, Stage I,
//           Stage II with that backend (cpu, gpu; none for off), then Stage III
//           (inter_object_distance), all of it timed. `--voronoi off,cpu,gpu` puts the three
//           side by side; gpu needs an EGL/OpenGL 4.3 context (here Mesa's llvmpipe when the
//           machine has no GPU) and is left out with a note when none can be made.
//   FCL     build: one BVHModel<OBBRSS> per object from this frame's positions (the objects
//           deform, so a frame has to rebuild them) and a DynamicAABBTree broad phase
//           (registerObjects + setup); query: for each object, manager.distance(object)
//           with a callback that skips the object itself and keeps the nearest other one.
// Each is run --repeat times; the fastest run is reported. FCL's builds and queries are spread
// over --fcl-threads threads (default: --threads), one object per task, so that both sides get
// the same cores. The per-object distances of the two must agree within a relative 1e-6;
// every disagreement is printed and makes the exit status 1.
#include "app/allocator.hpp"
#include "bench/bench_common.hpp"
#include "core/errors.hpp"
#include "core/broad_phase/object_broad_phase.hpp"
#include "core/query/inter_distance.hpp"
#include "core/voronoi/stage2.hpp"
#include "gl/egl_context.hpp"
#include "gl/voronoi_backend.hpp"
#include "io/scene_source.hpp"

#include <CLI/CLI.hpp>
#include <fcl/fcl.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <functional>
#include <iostream>
#include <limits>
#include <memory>
#include <optional>
#include <string>
#include <thread>
#include <vector>

namespace {

using Clock = std::chrono::steady_clock;

double ms_since(Clock::time_point t0) {
  return std::chrono::duration<double, std::milli>(Clock::now() - t0).count();
}

/// Runs fn(i) for i in [0, n) on `threads` threads, handing out indices one at a time.
void parallel_for(std::size_t n, int threads, const std::function<void(std::size_t)>& fn) {
  if (threads <= 1 || n <= 1) {
    for (std::size_t i = 0; i < n; ++i) fn(i);
    return;
  }
  std::atomic<std::size_t> next{0};
  auto worker = [&] {
    for (std::size_t i; (i = next.fetch_add(1)) < n;) fn(i);
  };
  std::vector<std::thread> pool;
  for (int t = 1; t < threads; ++t) pool.emplace_back(worker);
  worker();
  for (auto& th : pool) th.join();
}

// ---------------------------------------------------------------------------------------------
// FCL side

/// One object's nearest other object, as FCL finds it.
struct FclNearest {
  int object = -1;  ///< -1: no other object
  double distance = std::numeric_limits<double>::infinity();
};

struct FclRun {
  std::vector<FclNearest> per_object;
  double build_ms = 0;
  double query_ms = 0;
  double total_ms() const { return build_ms + query_ms; }
};

/// State of one manager.distance() call: the query object and the best answer so far.
struct NearestSearch {
  fcl::CollisionObjectd* self = nullptr;
  fcl::DistanceRequestd request;
  FclNearest best;
};

/// Broad-phase callback: exact mesh–mesh distance from the query object to a candidate.
/// `dist` is the manager's pruning bound: subtrees farther than it are not visited. Returns
/// true (stop) once the query object is found touching another one, as FCL's own default
/// distance callback does.
bool nearest_callback(fcl::CollisionObjectd* o1, fcl::CollisionObjectd* o2, void* data,
                      double& dist) {
  auto* search = static_cast<NearestSearch*>(data);
  fcl::CollisionObjectd* other = (o1 == search->self) ? o2 : o1;
  if (other == search->self) return false;  // the query object's own leaf

  fcl::DistanceResultd result;
  fcl::distance(search->self, other, search->request, result);
  // Without signed distance, FCL reports intersecting meshes as 0 or a negative value.
  const double d = std::max(0.0, result.min_distance);
  const int id = *static_cast<const int*>(other->getUserData());
  if (d < search->best.distance || (d == search->best.distance && id < search->best.object))
    search->best = {id, d};
  dist = search->best.distance;
  return dist <= 0;
}

/// Builds FCL's models and broad phase from the frame's positions and finds every object's
/// nearest other object.
FclRun run_fcl(const vproxq::Frame& frame, int threads) {
  const std::size_t n = frame.objects.size();
  FclRun run;
  run.per_object.resize(n);
  std::vector<int> ids(n);
  std::vector<std::unique_ptr<fcl::CollisionObjectd>> objects(n);

  const auto t_build = Clock::now();
  parallel_for(n, threads, [&](std::size_t i) {
    const vproxq::Object& obj = frame.objects[i];
    std::vector<fcl::Vector3d> points(obj.positions.begin(), obj.positions.end());
    std::vector<fcl::Triangle> triangles;
    triangles.reserve(obj.topology->faces.size());
    for (const vproxq::Face& f : obj.topology->faces)
      triangles.emplace_back(static_cast<std::size_t>(f[0]), static_cast<std::size_t>(f[1]),
                             static_cast<std::size_t>(f[2]));
    auto model = std::make_shared<fcl::BVHModel<fcl::OBBRSSd>>();
    model->beginModel(static_cast<int>(triangles.size()), static_cast<int>(points.size()));
    model->addSubModel(points, triangles);
    model->endModel();
    objects[i] = std::make_unique<fcl::CollisionObjectd>(model);  // computes its AABB
    ids[i] = static_cast<int>(i);
    objects[i]->setUserData(&ids[i]);
  });
  fcl::DynamicAABBTreeCollisionManagerd manager;
  std::vector<fcl::CollisionObjectd*> raw(n);
  for (std::size_t i = 0; i < n; ++i) raw[i] = objects[i].get();
  manager.registerObjects(raw);
  manager.setup();
  run.build_ms = ms_since(t_build);

  const auto t_query = Clock::now();
  parallel_for(n, threads, [&](std::size_t i) {
    NearestSearch search;
    search.self = objects[i].get();
    manager.distance(objects[i].get(), &search, nearest_callback);
    run.per_object[i] = search.best;
  });
  run.query_ms = ms_since(t_query);
  return run;
}

// ---------------------------------------------------------------------------------------------
// Comparison

/// Agreement asked of the two answers: FCL's OBBRSS mesh distance is exact up to rounding.
constexpr double kRelativeTolerance = 1e-6;
/// Floor for distances near 0 (touching objects), relative to the frame's bounding-box
/// diagonal: the rounding error of a triangle distance at that coordinate magnitude.
constexpr double kAbsoluteToleranceOfSize = 1e-12;

double bounding_diagonal(const vproxq::Frame& frame) {
  vproxq::Vec3 lo = vproxq::Vec3::Constant(vproxq::kInfinity), hi = -lo;
  for (const auto& obj : frame.objects)
    for (const auto& p : obj.positions) {
      lo = lo.cwiseMin(p);
      hi = hi.cwiseMax(p);
    }
  return (hi - lo).norm();
}

struct Agreement {
  int mismatches = 0;       ///< distances that differ beyond the tolerance
  int other_nearest = 0;    ///< same distance, different nearest object (a tie)
};

Agreement compare(const vproxq::Frame& frame, const std::vector<vproxq::InterObjectDistance>& ours,
                  const std::vector<FclNearest>& fcl, int max_printed) {
  Agreement a;
  const double abs_tol = kAbsoluteToleranceOfSize * bounding_diagonal(frame);
  for (std::size_t i = 0; i < frame.objects.size(); ++i) {
    const double dv = i < ours.size() ? ours[i].distance : vproxq::kInfinity;
    const int nv = i < ours.size() ? ours[i].nearest_object : -1;
    const double df = fcl[i].distance;
    const bool both_inf = std::isinf(dv) && std::isinf(df);
    const double tol = kRelativeTolerance * std::max(std::abs(dv), std::abs(df)) + abs_tol;
    const bool agree = both_inf || std::abs(dv - df) <= tol;
    if (!agree) {
      if (a.mismatches++ < max_printed)
        std::printf("  MISMATCH frame %d object %zu (%s): vproxq nearest %d at %.17g, "
                    "FCL nearest %d at %.17g\n",
                    frame.index, i, frame.objects[i].name.c_str(), nv, dv, fcl[i].object, df);
    } else if (nv != fcl[i].object) {
      ++a.other_nearest;
    }
  }
  return a;
}

// ---------------------------------------------------------------------------------------------
// Command line

struct Options {
  std::string scene;
  int threads = 2;
  std::optional<int> fcl_threads;
  std::string frames;  ///< "A:B", "A:", ":B" or "A"; empty: all
  int repeat = 3;
  std::string json;  ///< also write the per-frame numbers here (for vproxq-report)
  std::string voronoi = "off";  ///< comma-separated Stage II backends to time: off, cpu, gpu
  int grid = 0;                 ///< Stage II grid (0: vproxq's default)
};

/// One Stage II backend to time (none for "off").
struct Backend {
  std::string name;
  std::optional<vproxq::gl::Context> context;
  std::unique_ptr<vproxq::DiscreteVoronoiBackend> stage2;
};

/// The backends of --voronoi, in the order given; gpu is dropped with a note when no context
/// can be made. (Held by pointer: a GL backend refers to its context, which must not move.)
std::vector<std::unique_ptr<Backend>> make_backends(const Options& opt) {
  std::vector<std::unique_ptr<Backend>> out;
  std::size_t start = 0;
  while (start <= opt.voronoi.size()) {
    const std::size_t comma = std::min(opt.voronoi.find(',', start), opt.voronoi.size());
    const std::string name = opt.voronoi.substr(start, comma - start);
    start = comma + 1;
    if (name != "off" && name != "cpu" && name != "gpu")
      throw vproxq::UsageError("--voronoi '" + opt.voronoi + "': '" + name + "' is not off, cpu or gpu");
    for (const auto& b : out)
      if (b->name == name) throw vproxq::UsageError("--voronoi '" + opt.voronoi + "': '" + name + "' is given twice");
    auto b = std::make_unique<Backend>();
    b->name = name;
    if (name == "cpu") b->stage2 = vproxq::make_cpu_voronoi_backend(opt.threads);
    if (name == "gpu") {
      vproxq::gl::ContextResult r = vproxq::gl::try_create_context({});
      if (!r) {
        std::printf("note: --voronoi gpu left out: %s\n", r.error.c_str());
        continue;
      }
      b->context.emplace(std::move(*r.context));
      b->stage2 = std::make_unique<vproxq::gl::GlVoronoiBackend>(*b->context);
      std::printf("gpu: %s\n", b->context->renderer().c_str());
    }
    out.push_back(std::move(b));
  }
  if (out.empty()) throw vproxq::UsageError("--voronoi '" + opt.voronoi + "': no backend left to time");
  return out;
}

/// vproxq's inter-object distance with `b`: boxes, Stage I, Stage II (unless off), Stage III.
vproxq::InterDistanceOutput run_vproxq(const vproxq::Frame& frame, Backend& b, const Options& opt) {
  const vproxq::FrameBoxes boxes = vproxq::FrameBoxes::compute(frame, opt.threads);
  const vproxq::ObjectBroadPhase stage1 = vproxq::object_broad_phase(frame, boxes, opt.threads);
  vproxq::InterDistanceOptions vopt;
  vopt.threads = opt.threads;
  vproxq::VoronoiBounds bounds;
  if (b.stage2) {
    bounds = vproxq::compute_voronoi_bounds(frame, boxes, stage1, *b.stage2, opt.grid, opt.threads);
    vopt.voronoi = &bounds;
  }
  return vproxq::inter_object_distance(frame, boxes, stage1, vopt);
}

/// One frame's numbers, for --json.
struct FrameTiming {
  std::size_t frame = 0, objects = 0;
  long long triangles = 0, touching = 0;
  std::vector<double> vproxq_ms;  ///< per backend, in --voronoi's order
  double fcl_build_ms = 0, fcl_query_ms = 0;
  int mismatches = 0;
};

/// Writes --json: {"fcl_version", "threads", "fcl_threads", "repeat", "backends", "frames":
/// [...]} via a temporary file and a rename, so a reader never sees half of it. Each frame's
/// "vproxq_ms" is the first backend's time (what vproxq-report reads), "vproxq_ms_by_backend"
/// all of them.
void write_json(const Options& opt, int fcl_threads, const std::vector<std::unique_ptr<Backend>>& backends,
                const std::vector<FrameTiming>& rows) {
  std::string text = "{\n  \"tool\": \"vproxq-bench-fcl\",\n  \"fcl_version\": \"" FCL_VERSION "\",\n";
  char line[512];
  std::snprintf(line, sizeof line, "  \"threads\": %d,\n  \"fcl_threads\": %d,\n  \"repeat\": %d,\n  \"backends\": [",
                opt.threads, fcl_threads, opt.repeat);
  text += line;
  for (std::size_t b = 0; b < backends.size(); ++b) text += (b ? ", \"" : "\"") + backends[b]->name + "\"";
  text += "],\n  \"frames\": [";
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const FrameTiming& r = rows[i];
    std::snprintf(line, sizeof line,
                  "%s\n    {\"frame\": %zu, \"objects\": %zu, \"triangles\": %lld, "
                  "\"touching\": %lld, \"vproxq_ms\": %.17g, \"fcl_build_ms\": %.17g, "
                  "\"fcl_query_ms\": %.17g, \"mismatches\": %d, \"vproxq_ms_by_backend\": {",
                  i ? "," : "", r.frame, r.objects, r.triangles, r.touching, r.vproxq_ms[0],
                  r.fcl_build_ms, r.fcl_query_ms, r.mismatches);
    text += line;
    for (std::size_t b = 0; b < backends.size(); ++b) {
      std::snprintf(line, sizeof line, "%s\"%s\": %.17g", b ? ", " : "", backends[b]->name.c_str(), r.vproxq_ms[b]);
      text += line;
    }
    text += "}}";
  }
  text += "\n  ]\n}\n";
  vproxq::bench::write_file_atomically(opt.json, text);
}

/// Whether two backends' answers are the same, bit for bit (they must be: Stage II only culls).
bool same_answers(const std::vector<vproxq::InterObjectDistance>& a, const std::vector<vproxq::InterObjectDistance>& b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i)
    if (a[i].distance != b[i].distance || a[i].nearest_object != b[i].nearest_object) return false;
  return true;
}

int run(const Options& opt) {
  const vproxq::SceneSource scene = vproxq::SceneSource::open(opt.scene);
  const auto [first, last] = vproxq::bench::frame_range(opt.frames, scene.frame_count());
  const int fcl_threads = opt.fcl_threads.value_or(opt.threads);
  std::vector<std::unique_ptr<Backend>> backends = make_backends(opt);
  const std::size_t nb = backends.size();

  std::printf("scene %s (%s): frames %zu..%zu of %zu; vproxq threads %d, FCL %s threads %d; "
              "best of %d run%s\n",
              opt.scene.c_str(), scene.name().c_str(), first, last - 1, scene.frame_count(),
              opt.threads, FCL_VERSION, fcl_threads, opt.repeat, opt.repeat > 1 ? "s" : "");
#ifndef NDEBUG
  std::printf("warning: built without NDEBUG (not a Release build): timings are not meaningful\n");
#endif
  auto column = [&](const auto& b) { return nb == 1 ? std::string("vproxq ms") : b->name + " ms"; };
  std::printf("%6s %8s %10s %8s", "frame", "objects", "triangles", "touching");
  for (const auto& b : backends) std::printf(" %11s", column(b).c_str());
  std::printf(" %13s %13s %13s %10s", "FCL build ms", "FCL query ms", "FCL total ms",
              nb == 1 ? "FCL/vproxq" : ("FCL/" + backends[0]->name).c_str());
  for (std::size_t b = 1; b < nb; ++b) std::printf(" %10s", ("FCL/" + backends[b]->name).c_str());
  for (std::size_t b = 1; b < nb; ++b) std::printf(" %10s", (backends[0]->name + "/" + backends[b]->name).c_str());
  std::printf(" %9s\n", "mismatch");

  std::vector<double> sum_v(nb, 0.0);
  double sum_b = 0, sum_q = 0, sum_t = 0, sum_ratio = 0;
  long long sum_tris = 0;
  int frames = 0, mismatches = 0, ties = 0, backend_mismatches = 0;
  std::vector<FrameTiming> rows;
  for (std::size_t k = first; k < last; ++k) {
    const vproxq::Frame frame = scene.load_frame(k);
    long long tris = 0;
    for (const auto& obj : frame.objects) tris += obj.num_triangles();

    std::vector<double> best_v(nb, vproxq::kInfinity);
    std::vector<vproxq::InterObjectDistance> ours;
    for (std::size_t b = 0; b < nb; ++b)
      for (int r = 0; r < opt.repeat; ++r) {
        const auto t0 = Clock::now();
        vproxq::InterDistanceOutput out = run_vproxq(frame, *backends[b], opt);
        best_v[b] = std::min(best_v[b], ms_since(t0));
        if (b == 0 && r == 0) {
          ours = std::move(out.per_object);
        } else if (r == 0 && !same_answers(ours, out.per_object)) {
          ++backend_mismatches;
          std::printf("  MISMATCH frame %zu: --voronoi %s and %s give different answers\n", k,
                      backends[0]->name.c_str(), backends[b]->name.c_str());
        }
      }

    FclRun best_f;
    std::vector<FclNearest> theirs;
    for (int r = 0; r < opt.repeat; ++r) {
      FclRun f = run_fcl(frame, fcl_threads);
      if (r == 0) theirs = f.per_object;
      if (r == 0 || f.total_ms() < best_f.total_ms()) best_f = std::move(f);
    }

    const Agreement a = compare(frame, ours, theirs, 10);
    const auto touching =
        std::count_if(ours.begin(), ours.end(),
                      [](const vproxq::InterObjectDistance& d) { return d.distance == 0; });
    mismatches += a.mismatches;
    ties += a.other_nearest;
    const double ratio = best_f.total_ms() / best_v[0];
    std::printf("%6zu %8zu %10lld %8td", k, frame.objects.size(), tris, touching);
    for (double v : best_v) std::printf(" %11.2f", v);
    std::printf(" %13.2f %13.2f %13.2f", best_f.build_ms, best_f.query_ms, best_f.total_ms());
    for (double v : best_v) std::printf(" %10.2f", best_f.total_ms() / v);
    for (std::size_t b = 1; b < nb; ++b) std::printf(" %10.2f", best_v[0] / best_v[b]);
    std::printf(" %9d\n", a.mismatches);
    std::fflush(stdout);
    rows.push_back({k, frame.objects.size(), tris, static_cast<long long>(touching), best_v,
                    best_f.build_ms, best_f.query_ms, a.mismatches});
    for (std::size_t b = 0; b < nb; ++b) sum_v[b] += best_v[b];
    sum_b += best_f.build_ms;
    sum_q += best_f.query_ms;
    sum_t += best_f.total_ms();
    sum_ratio += ratio;
    sum_tris += tris;
    ++frames;
  }
  std::printf("%6s %8s %10.0f %8s", "mean", "", static_cast<double>(sum_tris) / frames, "");
  for (double v : sum_v) std::printf(" %11.2f", v / frames);
  std::printf(" %13.2f %13.2f %13.2f", sum_b / frames, sum_q / frames, sum_t / frames);
  for (double v : sum_v) std::printf(" %10.2f", sum_t / v);
  for (std::size_t b = 1; b < nb; ++b) std::printf(" %10.2f", sum_v[0] / sum_v[b]);
  std::printf(" %9d\n", mismatches);
  std::printf("(mean ratio = mean FCL total / mean vproxq; per-frame ratios average %.2f%s)\n",
              sum_ratio / frames, nb > 1 ? (" for " + backends[0]->name).c_str() : "");
  if (nb > 1)
    std::printf("vproxq: boxes, Stage I, Stage II (%s) and Stage III; %s/X = mean %s time over mean X time\n",
                opt.grid > 0 ? ("--grid " + std::to_string(opt.grid)).c_str() : "default grid",
                backends[0]->name.c_str(), backends[0]->name.c_str());
  std::printf("touching: objects at distance 0 (touching or overlapping another)\n");
  if (!opt.json.empty()) write_json(opt, fcl_threads, backends, rows);
  if (ties > 0)
    std::printf("%d object(s) with a different nearest object at the same distance (ties: FCL "
                "stops at the first touching object, vproxq reports the smallest id)\n",
                ties);
  if (backend_mismatches > 0) {
    std::printf("%d frame(s) where the backends' answers differ\n", backend_mismatches);
    return 1;
  }
  if (mismatches > 0) {
    std::printf("%d distance(s) disagree beyond relative %g\n", mismatches, kRelativeTolerance);
    return 1;
  }
  std::printf("all distances agree within relative %g%s\n", kRelativeTolerance,
              nb > 1 ? "; every backend gives the same answers" : "");
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
  vproxq::keep_freed_memory_for_reuse();  // as vproxq does
  CLI::App app{"vproxq-bench-fcl: times vproxq's inter-object distance against FCL " FCL_VERSION
               " (BVHModel<OBBRSS> per object + DynamicAABBTree broad phase), frame by frame, "
               "and checks that the two agree."};
  Options opt;
  app.add_option("scene", opt.scene, "scene.json or mesh file")->required();
  app.add_option("--threads", opt.threads, "vproxq worker threads")
      ->check(CLI::Range(1, 1024))
      ->capture_default_str();
  app.add_option("--fcl-threads", opt.fcl_threads,
                 "threads for FCL's per-object builds and queries (default: --threads)")
      ->check(CLI::Range(1, 1024));
  app.add_option("--frames", opt.frames, "frames A:B (A..B-1; A: and :B also work), default all");
  app.add_option("--repeat", opt.repeat, "runs per frame and side; the fastest is reported")
      ->check(CLI::Range(1, 1000))
      ->capture_default_str();
  app.add_option("--json", opt.json,
                 "also write the per-frame timings to this JSON file (read by vproxq-report)");
  app.add_option("--voronoi", opt.voronoi,
                 "comma-separated Stage II backends to time side by side: off, cpu, gpu")
      ->capture_default_str();
  app.add_option("--grid", opt.grid, "Stage II grid, cells along the longest axis (default: vproxq's)")
      ->check(CLI::Range(1, 4096));
  return vproxq::bench::guarded_main("vproxq-bench-fcl", app, argc, argv, [&] { return run(opt); });
}
