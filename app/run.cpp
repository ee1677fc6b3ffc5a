#include "app/config.hpp"
#include "app/progress.hpp"
#include "core/errors.hpp"
#include "core/parallel.hpp"
#include "core/query/ccd.hpp"
#include "core/query/inter_distance.hpp"
#include "core/query/intersecting_pairs.hpp"
#include "core/query/penetration_depth.hpp"
#include "core/query/intra_distance.hpp"
#include "core/timer.hpp"
#include "core/voronoi/self_stage2.hpp"
#include "core/voronoi/ccd_stage2.hpp"
#include "core/voronoi/stage2.hpp"
#include "gl/egl_context.hpp"
#include "gl/ccd_voxel_backend.hpp"
#include "gl/self_voronoi_backend.hpp"
#include "gl/voronoi_backend.hpp"
#include "io/output.hpp"
#include "io/pipeline.hpp"
#include "io/scene_source.hpp"

#include <algorithm>
#include <cerrno>
#include <cstdarg>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <thread>

namespace vproxq {
namespace {

/// Checks the requested queries and returns them in canonical order, without duplicates.
std::vector<std::string> canonical_queries(const std::vector<std::string>& requested,
                                           const char* origin) {
  for (const auto& r : requested) {
    if (std::find(kQueryNames.begin(), kQueryNames.end(), r) == kQueryNames.end())
      throw UsageError(std::string(origin) + ": unknown query '" + r +
                       "'; valid queries: " + query_names_list());
  }
  std::vector<std::string> out;
  for (const auto q : kQueryNames)
    if (std::find(requested.begin(), requested.end(), q) != requested.end()) out.emplace_back(q);
  if (out.empty()) throw UsageError(std::string(origin) + ": no query given; valid queries: " + query_names_list());
  return out;
}

/// Appends printf-formatted text to `out`.
[[gnu::format(printf, 2, 3)]] void appendf(std::string& out, const char* format, ...) {
  char small[512];
  std::va_list args;
  va_start(args, format);
  std::va_list again;
  va_copy(again, args);
  const int n = std::vsnprintf(small, sizeof small, format, args);
  va_end(args);
  if (n >= 0 && static_cast<std::size_t>(n) < sizeof small) {
    out.append(small, static_cast<std::size_t>(n));
  } else if (n > 0) {
    const std::size_t at = out.size();
    out.resize(at + static_cast<std::size_t>(n) + 1);
    std::vsnprintf(&out[at], static_cast<std::size_t>(n) + 1, format, again);
    out.resize(at + static_cast<std::size_t>(n));
  }
  va_end(again);
}

void ccd_summary(std::string& out, const CcdStepResult& c) {
  appendf(out, "  ccd -> frame %d: %zu vertex-face and %zu edge-edge pairs collide\n", c.to_frame, c.vf.size(),
          c.ee.size());
  for (const auto& p : c.pairs)
    appendf(out, "  ccd objects %4d %4d  earliest toi %.17g  primitive pairs %llu\n", p.objects[0], p.objects[1],
            p.toi, static_cast<unsigned long long>(p.primitive_pairs));
  for (const auto& s : c.skipped) appendf(out, "  ccd skipped object %d: %s\n", s.object, valid_utf8(s.reason).c_str());
}

/// One frame's summary, as printed without -o: the frame, intersecting pairs, PD, CCD, then per
/// object its nearest object and its intra-object minimum. Names as the result files write them.
void frame_summary(std::string& out, const FrameResult& r) {
  std::size_t tris = 0;
  for (const auto& o : r.objects) tris += static_cast<std::size_t>(o.triangles);
  appendf(out, "frame %d: %zu objects, %zu triangles, %.1f ms\n", r.frame, r.objects.size(), tris, r.time_ms.total);
  if (r.intersecting_pairs) appendf(out, "  intersecting triangle pairs: %zu\n", r.intersecting_pairs->size());
  if (r.pd)
    for (const auto& p : *r.pd) {
      if (p.status == PdStatus::Ok)
        appendf(out, "  pd %d-%d: depth %.17g direction (%.6g, %.6g, %.6g)\n", p.objects[0], p.objects[1], p.depth,
                p.direction.x(), p.direction.y(), p.direction.z());
      else if (p.reason == PdReason::SheetsNotSeparated)
        appendf(out, "  pd %d-%d: %s (%s: triangles %d and %d)\n", p.objects[0], p.objects[1], pd_status_name(p.status),
                pd_reason_name(p.reason), p.reason_features[0], p.reason_features[1]);
      else if (p.reason != PdReason::None)
        appendf(out, "  pd %d-%d: %s (%s: vertex %d)\n", p.objects[0], p.objects[1], pd_status_name(p.status),
                pd_reason_name(p.reason), p.reason_features[0]);
      else
        appendf(out, "  pd %d-%d: %s\n", p.objects[0], p.objects[1], pd_status_name(p.status));
    }
  if (r.ccd) ccd_summary(out, *r.ccd);
  std::vector<std::string> names;
  names.reserve(r.objects.size());
  for (const auto& o : r.objects) names.push_back(valid_utf8(o.name));
  if (r.inter)
    for (const auto& d : *r.inter) {
      const auto& name = names[static_cast<std::size_t>(d.object)];
      if (!d.has_nearest()) {
        appendf(out, "  %4d %-16s no other object\n", d.object, name.c_str());
        continue;
      }
      appendf(out, "  %4d %-16s nearest %4d %-16s distance %.17g  triangles %d,%d\n", d.object, name.c_str(),
              d.nearest_object, names[static_cast<std::size_t>(d.nearest_object)].c_str(), d.distance,
              d.triangles[0], d.triangles[1]);
    }
  if (r.intra)
    for (const auto& d : *r.intra) {
      const auto& name = names[static_cast<std::size_t>(d.object)];
      if (!d.has_pair())
        appendf(out, "  %4d %-16s self: no non-adjacent triangles\n", d.object, name.c_str());
      else
        appendf(out, "  %4d %-16s self distance %.17g  triangles %d,%d\n", d.object, name.c_str(), d.distance,
                d.triangles[0], d.triangles[1]);
    }
}

/// The Stage II backend of a run, and the GL context it may need (destroyed after it).
struct VoronoiStage {
  std::optional<gl::Context> context;
  std::unique_ptr<DiscreteVoronoiBackend> backend;
  std::unique_ptr<SelfVoronoiBackend> self_backend;  ///< the same kind, for the intra query
  std::unique_ptr<CcdVoxelBackend> ccd_backend;       ///< the same kind, for CCD's Stage II
};

/// The backends a run uses: the inter-object one always (its name and device go into the
/// output), the self one with the intra-object distance (`need_self`), CCD's with CCD
/// (`need_ccd`): a GL backend compiles its shaders when made.
VoronoiStage make_voronoi_stage(const Config& config, int threads, bool need_self, bool need_ccd) {
  VoronoiStage stage;
  if (config.voronoi == "off") return stage;
  gl::ContextOptions opts;
  opts.device_index = config.device;
  if (config.voronoi == "gpu") {
    stage.context.emplace(gl::create_context(opts));  // RuntimeError naming the failed call
  } else if (config.voronoi == "auto") {
    gl::ContextResult r = gl::try_create_context(opts);
    if (!r) {
      if (!config.quiet) std::fprintf(stderr, "vproxq: note: no GPU context (%s); using --voronoi=cpu\n", r.error.c_str());
    } else if (r.context->info().software) {
      // A software rasterizer (llvmpipe) is slower than the CPU twin: auto takes the CPU.
      if (!config.quiet) std::fprintf(stderr, "vproxq: note: only a software GL renderer (%s); using --voronoi=cpu\n", r.context->renderer().c_str());
    } else {
      stage.context.emplace(std::move(*r.context));
    }
  }
  if (stage.context) {
    // The CPU twin that redoes what a shader could not finish runs on --threads too.
    gl::GlVoronoiOptions gl_options;
    gl_options.cpu_threads = threads;
    gl::GlCcdVoxelOptions ccd_options;
    ccd_options.cpu_threads = threads;
    stage.backend = std::make_unique<gl::GlVoronoiBackend>(*stage.context, gl_options);
    if (need_self) stage.self_backend = std::make_unique<gl::GlSelfVoronoiBackend>(*stage.context, gl_options);
    if (need_ccd) stage.ccd_backend = std::make_unique<gl::GlCcdVoxelBackend>(*stage.context, ccd_options);
  } else {
    stage.backend = make_cpu_voronoi_backend(threads);
    if (need_self) stage.self_backend = make_cpu_self_voronoi_backend(threads);
    if (need_ccd) stage.ccd_backend = make_cpu_ccd_voxel_backend(threads);
  }
  return stage;
}

/// The stats of either Stage II (VoronoiBounds or SelfVoronoiBounds) for the output.
template <typename Bounds>
VoronoiFrameStats frame_stats(const Bounds& b, std::uint64_t samples) {
  VoronoiFrameStats v;
  v.grid_dims = b.grid.dims;
  v.cell = b.grid.cell;
  v.delta = b.delta;
  v.delta_precision = b.delta_precision;
  v.sample_voxels = b.sample_voxels;
  v.samples = samples;
  v.backend_triangles = b.backend_triangles;
  v.setup_ms = b.setup_ms;
  v.upload_ms = b.upload_ms;
  v.compute_ms = b.compute_ms;
  v.readback_ms = b.readback_ms;
  v.scan_ms = b.scan_ms;
  return v;
}

/// Intra-object results of static objects (scene "static"), by topology. A static object is
/// the same in every frame (read once: one topology, shared by the frames, and the same
/// positions), and its intra-object result depends on it alone, so it is computed on the first
/// frame of the run and reused on the others.
using StaticIntraCache = std::map<const Topology*, IntraObjectDistance>;

/// The intra-object ("self") part of the distance query: 2-ring bounds, the self Stage II when
/// a backend runs (at `grid` when given, else its own default), Stage III, for every object
/// but the static ones already in `statics` (whose results are copied from there). Its times
/// add to the frame's voronoi and exact times.
/// `intersecting` receives the intersecting pairs within the objects searched
/// (IntraDistanceOutput), and `left_out` the static objects not searched, for
/// intersecting_pairs().
void run_intra(const Frame& frame, const FrameBoxes& boxes, VoronoiStage& voronoi, int grid,
               int threads, FrameResult& result, StaticIntraCache& statics,
               std::vector<IntersectingPair>& intersecting, std::vector<std::uint8_t>& left_out) {
  Stopwatch sw;
  const std::size_t n = frame.objects.size();
  std::vector<std::uint8_t> known(n, 0);
  bool any_known = false;
  for (std::size_t i = 0; i < n; ++i)
    if (frame.objects[i].is_static && statics.count(frame.objects[i].topology.get()) != 0) known[i] = 1, any_known = true;
  const std::vector<std::uint8_t>* skip = any_known ? &known : nullptr;
  // The 2-ring bounds are the intra query's Stage I (paper 5.2.2): they count as "aabb".
  const auto ring2 = ring2_upper_bounds(frame, threads, skip);
  result.time_ms.intra_bounds = sw.elapsed_ms();
  result.time_ms.aabb += result.time_ms.intra_bounds;
  IntraDistanceOptions opts{threads, nullptr, skip};
  SelfVoronoiBounds bounds;
  sw.restart();
  if (voronoi.self_backend) {
    bounds = compute_self_voronoi_bounds(frame, boxes, ring2, *voronoi.self_backend, grid, threads, skip);
    opts.voronoi = &bounds;
    result.self_voronoi = frame_stats(bounds, bounds.samples);
    result.self_voronoi->sampled_triangles = bounds.sampled_triangles;
  }
  result.time_ms.intra_voronoi = sw.elapsed_ms();
  result.time_ms.voronoi += result.time_ms.intra_voronoi;
  IntraDistanceOutput d = intra_object_distance(frame, boxes, ring2, opts);
  result.time_ms.intra_exact = d.exact_ms;
  result.time_ms.exact += d.exact_ms;
  result.counters.intra_candidates = d.counters.intra_candidates;
  result.counters.intra_voronoi_culled = d.counters.intra_voronoi_culled;
  result.counters.intra_separation_culled = d.counters.intra_separation_culled;
  result.counters.intra_reused = d.counters.intra_reused;
  result.counters.intra_exact_tests = d.counters.intra_exact_tests;
  for (std::size_t i = 0; i < n; ++i) {
    const Object& o = frame.objects[i];
    if (known[i] != 0) {
      d.per_object[i] = statics.at(o.topology.get());
      d.per_object[i].object = static_cast<Index>(i);
    } else if (o.is_static) {
      statics.emplace(o.topology.get(), d.per_object[i]);
    }
  }
  result.intra = std::move(d.per_object);
  intersecting = std::move(d.intersecting);
  left_out = std::move(known);
}

}  // namespace

void run(const Config& config) {
  // The frame files are checked once the range is known: only those the run reads need exist.
  const SceneSource scene = SceneSource::open(config.scene_path, FrameFileCheck::Deferred);

  std::vector<std::string> queries =
      !config.queries.empty() ? canonical_queries(config.queries, "--queries")
      : !scene.queries().empty()
          ? canonical_queries(scene.queries(), (config.scene_path + ": \"queries\"").c_str())
          : std::vector<std::string>{"distance"};

  const long count = static_cast<long>(scene.frame_count());
  const long first = config.frames.first.value_or(0);
  const long last = std::min(config.frames.last.value_or(count), count);
  if (first >= count)
    throw UsageError("--frames: first frame " + std::to_string(first) + " is past the end (" +
                     config.scene_path + " has " + std::to_string(count) + (count == 1 ? " frame)" : " frames)"));

  const bool want_distance = std::find(queries.begin(), queries.end(), "distance") != queries.end();
  const bool want_pd = std::find(queries.begin(), queries.end(), "pd") != queries.end();
  const bool want_ccd = std::find(queries.begin(), queries.end(), "ccd") != queries.end();
  // The frames the run reads: first .. last-1, and frame last too with CCD when the scene has
  // it (CCD of frame k covers the step k -> k+1, also past the end of --frames).
  const long read_end = want_ccd ? std::min(last + 1, count) : last;
  scene.require_frames(static_cast<std::size_t>(first), static_cast<std::size_t>(read_end));

  RunInfo info;
  info.scene = config.scene_path;
  info.scene_name = scene.name();
  info.queries = queries;
  info.voronoi = config.voronoi;
  info.threads = resolve_threads(config.threads);
  const bool self = config.self.value_or(scene.self().value_or(true));
  info.self = self;
  // Options that no query of the run uses: said once, like the backend's in cli.cpp (which
  // notes --grid and --ccd-grid with --voronoi=off; here only with a backend, so as not to say
  // it twice).
  if (!config.quiet) {
    if (config.self.has_value() && !want_distance)
      std::fprintf(stderr, "vproxq: note: --self has no effect without the distance query\n");
    if (config.voronoi != "off" && config.grid > 0 && !want_distance)
      std::fprintf(stderr, "vproxq: note: --grid has no effect without the distance query\n");
    if (config.voronoi != "off" && config.ccd_grid > 0 && !want_ccd)
      std::fprintf(stderr, "vproxq: note: --ccd-grid has no effect without the ccd query\n");
  }
  info.frame_count = static_cast<std::size_t>(last - first);
  const int grid = config.grid > 0 ? config.grid : scene.grid().value_or(0);
  VoronoiStage voronoi = make_voronoi_stage(config, info.threads, want_distance && self, want_ccd);
  info.voronoi = voronoi.backend ? voronoi.backend->name() : "off";
  info.device = voronoi.backend ? voronoi.backend->device() : "";
  info.grid = voronoi.backend ? grid : 0;

  // Where --threads leaves a core free, frames are read ahead and written behind on background
  // threads, while a frame is computed; else in line: with every core computing, the overlap
  // took as long in all and made each query's time longer (report scenes, 2 threads on 2 cores:
  // funnel's query 137 -> 148 ms per frame, breaking's 25 -> 28).
  const unsigned cores = std::thread::hardware_concurrency();
  const double inline_ms = cores > 0 && static_cast<unsigned>(info.threads) < cores ? kInlineMs : kInfinity;
  std::unique_ptr<BackgroundWriter> writer;
  if (!config.output_dir.empty())
    writer = std::make_unique<BackgroundWriter>(std::make_unique<ResultWriter>(config.output_dir, info), inline_ms);

  // The next frame of a CCD step is loaded once and reused as the next frame of the loop.
  // Frames are read in order, each on a background thread while the one before it is in use
  // (see above; in line when reads are quick; `load` is the time the loop waited for them).
  FrameReadAhead reader(scene, static_cast<std::size_t>(first), static_cast<std::size_t>(read_end), inline_ms);
  std::optional<Frame> next_frame;
  StaticIntraCache static_intra;
  Progress progress(info.frame_count, !config.quiet);
  std::string summary;  ///< without -o: what is printed when the run ends
  for (long k = first; k < last; ++k) {
    Stopwatch total;
    FrameResult result;
    result.frame = static_cast<int>(k);
    Stopwatch sw;
    const Frame frame = next_frame && next_frame->index == k ? std::move(*next_frame) : reader.next();
    next_frame.reset();
    if (want_ccd && k + 1 < count) next_frame = reader.next();
    result.time_ms.load = sw.elapsed_ms();
    result.files = frame.files;
    for (std::size_t i = 0; i < frame.objects.size(); ++i) {
      const Object& o = frame.objects[i];
      result.objects.push_back({static_cast<Index>(i), o.name, o.num_vertices(), o.num_triangles(), o.is_static});
    }
    if (want_distance || want_pd) {
      sw.restart();
      const FrameBoxes boxes = FrameBoxes::compute(frame, info.threads);
      // Stage I's upper bounds and PNS serve the inter-object distance and Stage II's bands;
      // the intersecting pairs and PD alone need only the boxes.
      const ObjectBroadPhase stage1 = want_distance || voronoi.backend
                                          ? object_broad_phase(frame, boxes, info.threads)
                                          : ObjectBroadPhase{};
      result.time_ms.aabb = sw.elapsed_ms();
      InterDistanceOptions opts{info.threads, nullptr};
      std::vector<IntersectingPair> intra_pairs;
      std::vector<std::uint8_t> intra_left_out;
      VoronoiBounds bounds;
      if (voronoi.backend) {
        sw.restart();
        bounds = compute_voronoi_bounds(frame, boxes, stage1, *voronoi.backend, grid, info.threads);
        result.time_ms.voronoi = sw.elapsed_ms();
        opts.voronoi = &bounds;
        result.voronoi = frame_stats(bounds, bounds.sample_voxels);
        result.voronoi->sampled_triangles = bounds.sampled_triangles;
      }
      if (want_distance) {
        InterDistanceOutput d = inter_object_distance(frame, boxes, stage1, opts);
        result.time_ms.exact = d.exact_ms;
        result.counters = d.counters;
        result.inter = std::move(d.per_object);
        if (self)
          run_intra(frame, boxes, voronoi, grid, info.threads, result, static_intra, intra_pairs, intra_left_out);
      }
      // Discrete collisions (paper 3.2), then local penetration depth (3.3) from them; their
      // time counts as exact tests. The pairs within the objects that the intra-object
      // distance searched come from its exact tests (it meets every such pair).
      sw.restart();
      IntersectingPairsOptions ip_options{info.threads, opts.voronoi, true};
      std::vector<double> object_distance;
      if (result.inter) {
        for (const InterObjectDistance& d : *result.inter) object_distance.push_back(d.distance);
        ip_options.object_distance = &object_distance;
      }
      if (want_distance && self) {
        ip_options.intra_pairs = &intra_pairs;
        ip_options.intra_skip = &intra_left_out;
      }
      IntersectingPairsOutput ip = intersecting_pairs(frame, boxes, ip_options);
      result.intersection_tests = ip.exact_tests;
      if (want_pd) result.pd = penetration_depth(frame, boxes, ip.pairs, {info.threads}).pairs;
      result.intersecting_pairs = std::move(ip.pairs);
      result.time_ms.exact += sw.elapsed_ms();
    }
    if (next_frame) {
      // The next frame's objects in this frame's order: by name where the files list them in
      // another order, pieces of broken meshes by their vertices (ccd_counterparts()).
      const std::optional<Frame> reordered = ccd_counterparts(frame, *next_frame);
      const Frame& to = reordered ? *reordered : *next_frame;
      sw.restart();
      const CcdSweep sweep = CcdSweep::compute(frame, to, info.threads);
      const double sweep_ms = sw.elapsed_ms();
      // Stage II for CCD, inside: on the triangles of the pairs Stage I leaves, records on the
      // host, voxels and co-occupancy on the backend.
      CcdOptions ccd_options{info.threads};
      ccd_options.voxel_backend = voronoi.backend ? voronoi.ccd_backend.get() : nullptr;
      ccd_options.voxel_grid = config.ccd_grid;
      CcdStepResult c = continuous_collisions(frame, to, sweep, ccd_options);
      c.aabb_ms += sweep_ms;
      result.time_ms.aabb += c.aabb_ms;
      result.time_ms.voronoi += c.voronoi_ms;
      result.time_ms.exact += c.exact_ms;
      result.ccd = std::move(c);
    }
    result.time_ms.total = total.elapsed_ms();
    if (writer) {
      // write_frame() fills in and adds its own time before serialising the stats.
      writer->write_frame(std::move(result));
    } else if (!config.quiet) {
      frame_summary(summary, result);
    }
    progress.update(static_cast<std::size_t>(k - first + 1));
  }
  progress.finish();
  if (!summary.empty()) {
    // Printed whole at the end, so that a run that fails part-way (a bad frame) prints none of
    // it, as it writes no files. A failed write is a runtime error (a full disk, a file-size
    // limit: SIGXFSZ is ignored, see app/cli.cpp); a closed pipe ends the run by SIGPIPE.
    errno = 0;
    const bool written = std::fwrite(summary.data(), 1, summary.size(), stdout) == summary.size();
    if (!written || std::fflush(stdout) != 0)
      throw RuntimeError(std::string("cannot write the summary to standard output: ") +
                         (errno != 0 ? std::strerror(errno) : "write error"));
  }
  if (writer) {
    writer->commit();
    if (!config.quiet)
      std::fprintf(stderr, "vproxq: wrote %s/results.json and %s/results.h5 (%zu frame%s)\n",
                   config.output_dir.c_str(), config.output_dir.c_str(), info.frame_count,
                   info.frame_count == 1 ? "" : "s");
  }
}

}  // namespace vproxq
