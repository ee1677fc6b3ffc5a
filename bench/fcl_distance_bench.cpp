// vproxq-bench-fcl: per-frame inter-object distance (every object's nearest other object and
// the separation distance), vproxq against FCL 0.7, on the frames of a scene.
//
//   vproxq-bench-fcl bench-out/scene.json --threads 2 --frames 0:5 --repeat 3 [--json out.json]
//
// For each frame, with the frame already loaded (loading is not timed):
//   vproxq  inter_object_distance(frame, {threads}).
//   FCL     build: one BVHModel<OBBRSS> per object from this frame's positions (the objects
//           deform, so a frame has to rebuild them) and a DynamicAABBTree broad phase
//           (registerObjects + setup); query: for each object, manager.distance(object)
//           with a callback that skips the object itself and keeps the nearest other one.
// Each is run --repeat times; the fastest run is reported. FCL's builds and queries are spread
// over --fcl-threads threads (default: --threads), one object per task, so that both sides get
// the same cores. The per-object distances of the two must agree within a relative 1e-6;
// every disagreement is printed and makes the exit status 1.
#include "bench/bench_common.hpp"
#include "core/errors.hpp"
#include "core/query/inter_distance.hpp"
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
};

/// One frame's numbers, for --json.
struct FrameTiming {
  std::size_t frame = 0, objects = 0;
  long long triangles = 0, touching = 0;
  double vproxq_ms = 0, fcl_build_ms = 0, fcl_query_ms = 0;
  int mismatches = 0;
};

/// Writes --json: {"fcl_version", "threads", "fcl_threads", "repeat", "frames": [...]}, via a
/// temporary file and a rename, so a reader never sees half of it.
void write_json(const Options& opt, int fcl_threads, const std::vector<FrameTiming>& rows) {
  std::string text = "{\n  \"tool\": \"vproxq-bench-fcl\",\n  \"fcl_version\": \"" FCL_VERSION "\",\n";
  char line[512];
  std::snprintf(line, sizeof line,
                "  \"threads\": %d,\n  \"fcl_threads\": %d,\n  \"repeat\": %d,\n  \"frames\": [",
                opt.threads, fcl_threads, opt.repeat);
  text += line;
  for (std::size_t i = 0; i < rows.size(); ++i) {
    const FrameTiming& r = rows[i];
    std::snprintf(line, sizeof line,
                  "%s\n    {\"frame\": %zu, \"objects\": %zu, \"triangles\": %lld, "
                  "\"touching\": %lld, \"vproxq_ms\": %.17g, \"fcl_build_ms\": %.17g, "
                  "\"fcl_query_ms\": %.17g, \"mismatches\": %d}",
                  i ? "," : "", r.frame, r.objects, r.triangles, r.touching, r.vproxq_ms,
                  r.fcl_build_ms, r.fcl_query_ms, r.mismatches);
    text += line;
  }
  text += "\n  ]\n}\n";
  vproxq::bench::write_file_atomically(opt.json, text);
}

int run(const Options& opt) {
  const vproxq::SceneSource scene = vproxq::SceneSource::open(opt.scene);
  const auto [first, last] = vproxq::bench::frame_range(opt.frames, scene.frame_count());
  const int fcl_threads = opt.fcl_threads.value_or(opt.threads);

  std::printf("scene %s (%s): frames %zu..%zu of %zu; vproxq threads %d, FCL %s threads %d; "
              "best of %d run%s\n",
              opt.scene.c_str(), scene.name().c_str(), first, last - 1, scene.frame_count(),
              opt.threads, FCL_VERSION, fcl_threads, opt.repeat, opt.repeat > 1 ? "s" : "");
#ifndef NDEBUG
  std::printf("warning: built without NDEBUG (not a Release build): timings are not meaningful\n");
#endif
  std::printf("%6s %8s %10s %8s %11s %13s %13s %13s %10s %9s\n", "frame", "objects",
              "triangles", "touching", "vproxq ms", "FCL build ms", "FCL query ms", "FCL total ms",
              "FCL/vproxq", "mismatch");

  double sum_v = 0, sum_b = 0, sum_q = 0, sum_t = 0, sum_ratio = 0;
  long long sum_tris = 0;
  int frames = 0, mismatches = 0, ties = 0;
  std::vector<FrameTiming> rows;
  for (std::size_t k = first; k < last; ++k) {
    const vproxq::Frame frame = scene.load_frame(k);
    long long tris = 0;
    for (const auto& obj : frame.objects) tris += obj.num_triangles();

    vproxq::InterDistanceOptions vopt;
    vopt.threads = opt.threads;
    double best_v = vproxq::kInfinity;
    std::vector<vproxq::InterObjectDistance> ours;
    for (int r = 0; r < opt.repeat; ++r) {
      const auto t0 = Clock::now();
      vproxq::InterDistanceOutput out = vproxq::inter_object_distance(frame, vopt);
      best_v = std::min(best_v, ms_since(t0));
      if (r == 0) ours = std::move(out.per_object);
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
    const double ratio = best_f.total_ms() / best_v;
    std::printf("%6zu %8zu %10lld %8td %11.2f %13.2f %13.2f %13.2f %10.2f %9d\n", k,
                frame.objects.size(), tris, touching, best_v, best_f.build_ms, best_f.query_ms,
                best_f.total_ms(), ratio, a.mismatches);
    std::fflush(stdout);
    rows.push_back({k, frame.objects.size(), tris, static_cast<long long>(touching), best_v,
                    best_f.build_ms, best_f.query_ms, a.mismatches});
    sum_v += best_v;
    sum_b += best_f.build_ms;
    sum_q += best_f.query_ms;
    sum_t += best_f.total_ms();
    sum_ratio += ratio;
    sum_tris += tris;
    ++frames;
  }
  std::printf("%6s %8s %10.0f %8s %11.2f %13.2f %13.2f %13.2f %10.2f %9d\n", "mean", "",
              static_cast<double>(sum_tris) / frames, "", sum_v / frames, sum_b / frames,
              sum_q / frames, sum_t / frames, sum_t / sum_v, mismatches);
  std::printf("(mean ratio = mean FCL total / mean vproxq; per-frame ratios average %.2f)\n",
              sum_ratio / frames);
  std::printf("touching: objects at distance 0 (touching or overlapping another)\n");
  if (!opt.json.empty()) write_json(opt, fcl_threads, rows);
  if (ties > 0)
    std::printf("%d object(s) with a different nearest object at the same distance (ties: FCL "
                "stops at the first touching object, vproxq reports the smallest id)\n",
                ties);
  if (mismatches > 0) {
    std::printf("%d distance(s) disagree beyond relative %g\n", mismatches, kRelativeTolerance);
    return 1;
  }
  std::printf("all distances agree within relative %g\n", kRelativeTolerance);
  return 0;
}

}  // namespace

int main(int argc, char** argv) {
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
  return vproxq::bench::guarded_main("vproxq-bench-fcl", app, argc, argv, [&] { return run(opt); });
}
