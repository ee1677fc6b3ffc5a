// vproxq-report: aggregates the benchmark runs of scripts/report.sh into a report like the
// paper's Table 1 and figures 13 and 14 (section 6.2).
//
//   vproxq-report --runs bench-out/report/runs --out bench-out/report [--machine FILE]
//
// Input, one folder per scene under --runs (scene order: the paper's, then by name):
//   <scene>/off/results.json, cpu/results.json, gpu/results.json   vproxq -o, per Stage II mode
//   <scene>/grid-<N>/results.json                                    vproxq --voronoi=MODE --grid N
//   <scene>/fcl.json                                                 vproxq-bench-fcl --json
//   <scene>/pns.json (optional)                                      vproxq-bench-pns --json
//   <scene>/<run>/error.txt or <scene>/fcl-error.txt                 why a run failed ("n/a")
// Output in --out: report.md (the tables), results.csv (every per-frame number of every run),
// summary.csv (the per-run averages behind the tables), fig13.dat/.gp and fig14.dat/.gp (gnuplot
// scripts writing fig13.png and fig14.png; scripts/report.sh runs them). Times are the mean
// per frame of the query time: vproxq's total minus loading the frame.
// Every query's work is shown per mode (figure 13 per query): inter-object, intra-object,
// intersection and CCD tests, each the mean over the frames where that query ran ("–" in the
// report and an empty CSV field where it did not), and the query time split per query.
// Nothing is measured here; a number missing from the inputs is reported as n/a.
#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <map>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

namespace fs = std::filesystem;
using nlohmann::json;

namespace {

/// The paper's benchmarks in its order; other scenes follow by name.
const std::vector<std::string> kPaperOrder = {"skirt", "cloth-ball", "bowl", "funnel", "breaking"};
const std::vector<std::string> kModes = {"off", "cpu", "gpu"};

/// The queries whose exact tests the report shows separately (figure 13 per query): the
/// inter-object distance (stats.exact_tests, on frames with distance.inter), the intra-object
/// distance (stats.intra_exact_tests), the discrete intersection tests of the collision and PD
/// queries (stats.intersection_tests) and CCD's elementary tests (stats.ccd.elementary_tests).
enum QueryKind { kInter = 0, kIntra, kIntersect, kCcd, kQueryKinds };
const char* const kQueryKey[kQueryKinds] = {"inter", "intra", "intersection", "ccd"};
const char* const kQueryColumn[kQueryKinds] = {"inter_exact_tests", "intra_exact_tests",
                                               "intersection_tests", "ccd_elementary_tests"};
const char* const kQueryTitle[kQueryKinds] = {"inter-object exact tests", "intra-object exact tests",
                                              "intersection tests", "CCD elementary tests"};

/// Shown for a number whose query did not run (its key is absent from every frame).
const char* const kNotRun = "–";

using Opt = std::optional<double>;

/// One frame of one run, the numbers of results.json's "stats" (or of vproxq-bench-fcl).
/// Optional numbers are absent when their query did not run on the frame.
struct FrameRow {
  int frame = 0;
  long long objects = 0, triangles = 0;        ///< all objects, static ones included
  long long static_objects = 0, static_triangles = 0;
  std::array<long long, 3> grid{0, 0, 0};
  double load = 0, aabb = 0, voronoi = 0, exact = 0, total = 0;
  double exact_tests = 0, pns_pairs = 0, feature_pns = 0;
  double fcl_build = 0, fcl_query = 0, fcl_vproxq = 0;
  long long fcl_mismatches = 0;  ///< per-object distances where FCL and vproxq disagree
  std::array<Opt, kQueryKinds> tests;  ///< exact tests per query (QueryKind)
  Opt intra_candidates, intra_voronoi_culled;
  Opt ccd_vf_tests, ccd_ee_tests, ccd_triangle_pairs, ccd_culled_triangles, ccd_limit_hits,
      ccd_vf_pairs, ccd_ee_pairs;
  Opt intra_bounds, intra_voronoi, intra_exact;  ///< stats.time_ms.intra_*
  Opt ccd_aabb, ccd_voronoi, ccd_exact;          ///< stats.ccd.time_ms
  double query_ms() const { return total - load; }
  /// The intra-object distance's share of the query time (its three stages).
  Opt intra_ms() const {
    if (!intra_bounds && !intra_voronoi && !intra_exact) return std::nullopt;
    return intra_bounds.value_or(0) + intra_voronoi.value_or(0) + intra_exact.value_or(0);
  }
  /// CCD's share of the query time (stats.ccd.time_ms summed).
  Opt ccd_ms() const {
    if (!ccd_aabb && !ccd_voronoi && !ccd_exact) return std::nullopt;
    return ccd_aabb.value_or(0) + ccd_voronoi.value_or(0) + ccd_exact.value_or(0);
  }
  /// The rest of the query time: inter-object distance, intersecting pairs and PD (absent when
  /// none of them ran on the frame).
  Opt inter_pairs_pd_ms() const {
    if (!tests[kInter] && !tests[kIntersect]) return std::nullopt;
    return query_ms() - intra_ms().value_or(0) - ccd_ms().value_or(0);
  }
};

struct Run {
  std::string name;             ///< off, cpu, gpu, grid-N, fcl
  std::optional<std::string> error;
  std::vector<FrameRow> frames;
  std::string device;
  std::string voronoi;  ///< settings.voronoi: the backend that ran (off, cpu, gpu)
  std::string queries;
  int threads = 0;
  int grid_setting = 0;  ///< --grid of a grid-N run
};

struct Scene {
  std::string name;
  std::map<std::string, Run> runs;
  json pns;  ///< vproxq-bench-pns --json, or null where it did not run
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::string s((std::istreambuf_iterator<char>(in)), {});
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  return s;
}

double number(const json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_number() ? j[key].get<double>() : 0.0;
}

/// The number at j[key], absent when j is no object or has no such number.
Opt optional_number(const json& j, const char* key) {
  if (!j.is_object() || !j.contains(key) || !j[key].is_number()) return std::nullopt;
  return j[key].get<double>();
}

/// j[key] when it is an object, else an empty object (absent stats blocks).
json object_at(const json& j, const char* key) {
  return j.is_object() && j.contains(key) && j[key].is_object() ? j[key] : json::object();
}

Run read_vproxq_run(const std::string& name, const fs::path& dir) {
  Run run;
  run.name = name;
  if (fs::exists(dir / "error.txt")) {
    run.error = slurp(dir / "error.txt");
    return run;
  }
  const fs::path file = dir / "results.json";
  if (!fs::exists(file)) {
    run.error = "no results.json";
    return run;
  }
  std::ifstream in(file);
  const json j = json::parse(in);
  const json& settings = j.value("settings", json::object());
  if (settings.contains("device") && settings["device"].is_string())
    run.device = settings["device"].get<std::string>();
  if (settings.contains("voronoi") && settings["voronoi"].is_string())
    run.voronoi = settings["voronoi"].get<std::string>();
  run.threads = settings.value("threads", 0);
  if (settings.contains("grid") && settings["grid"].is_number()) run.grid_setting = settings["grid"].get<int>();
  for (const auto& q : j.value("queries", json::array()))
    run.queries += (run.queries.empty() ? "" : ",") + q.get<std::string>();
  for (const json& f : j.at("frames")) {
    FrameRow r;
    r.frame = f.value("frame", 0);
    for (const json& o : f.value("objects", json::array())) {
      ++r.objects;
      r.triangles += o.value("triangles", 0LL);
      if (o.value("static", false)) {
        ++r.static_objects;
        r.static_triangles += o.value("triangles", 0LL);
      }
    }
    const json st = object_at(f, "stats");
    const json t = object_at(st, "time_ms");
    r.load = number(t, "load");
    r.aabb = number(t, "aabb");
    r.voronoi = number(t, "voronoi");
    r.exact = number(t, "exact");
    r.total = number(t, "total");
    r.exact_tests = number(st, "exact_tests");
    r.pns_pairs = number(st, "pns_pairs");
    r.feature_pns = number(st, "feature_pns");
    // stats.exact_tests is always written; it counts inter-object tests when distance ran.
    const json distance = object_at(f, "distance");
    if (distance.contains("inter")) r.tests[kInter] = optional_number(st, "exact_tests");
    r.tests[kIntra] = optional_number(st, "intra_exact_tests");
    r.tests[kIntersect] = optional_number(st, "intersection_tests");
    r.intra_candidates = optional_number(st, "intra_candidates");
    r.intra_voronoi_culled = optional_number(st, "intra_voronoi_culled");
    r.intra_bounds = optional_number(t, "intra_bounds");
    r.intra_voronoi = optional_number(t, "intra_voronoi");
    r.intra_exact = optional_number(t, "intra_exact");
    if (st.contains("ccd") && st["ccd"].is_object()) {
      const json& c = st["ccd"];
      r.tests[kCcd] = optional_number(c, "elementary_tests");
      r.ccd_vf_tests = optional_number(c, "vf_tests");
      r.ccd_ee_tests = optional_number(c, "ee_tests");
      r.ccd_triangle_pairs = optional_number(c, "triangle_pairs");
      r.ccd_culled_triangles = optional_number(c, "culled_triangles");
      r.ccd_limit_hits = optional_number(c, "limit_hits");
      r.ccd_vf_pairs = optional_number(c, "vf_pairs");
      r.ccd_ee_pairs = optional_number(c, "ee_pairs");
      const json ct = object_at(c, "time_ms");
      r.ccd_aabb = optional_number(ct, "aabb");
      r.ccd_voronoi = optional_number(ct, "voronoi");
      r.ccd_exact = optional_number(ct, "exact");
    }
    if (st.contains("voronoi") && st["voronoi"].is_object() && st["voronoi"].contains("grid") &&
        st["voronoi"]["grid"].is_array() && st["voronoi"]["grid"].size() == 3)
      for (int k = 0; k < 3; ++k) r.grid[static_cast<size_t>(k)] = st["voronoi"]["grid"][static_cast<size_t>(k)].get<long long>();
    run.frames.push_back(r);
  }
  return run;
}

Run read_fcl_run(const fs::path& scene_dir) {
  Run run;
  run.name = "fcl";
  if (fs::exists(scene_dir / "fcl-error.txt")) {
    run.error = slurp(scene_dir / "fcl-error.txt");
    return run;
  }
  if (!fs::exists(scene_dir / "fcl.json")) {
    run.error = "not run";
    return run;
  }
  std::ifstream in(scene_dir / "fcl.json");
  const json j = json::parse(in);
  run.device = j.value("fcl_version", std::string());
  run.threads = j.value("fcl_threads", 0);
  for (const json& f : j.at("frames")) {
    FrameRow r;
    r.frame = f.value("frame", 0);
    r.objects = f.value("objects", 0LL);
    r.triangles = f.value("triangles", 0LL);
    r.fcl_build = number(f, "fcl_build_ms");
    r.fcl_query = number(f, "fcl_query_ms");
    r.fcl_vproxq = number(f, "vproxq_ms");
    r.fcl_mismatches = f.value("mismatches", 0LL);
    r.total = r.fcl_build + r.fcl_query;
    run.frames.push_back(r);
  }
  return run;
}

std::vector<Scene> read_scenes(const fs::path& runs_dir) {
  std::vector<Scene> scenes;
  for (const auto& e : fs::directory_iterator(runs_dir)) {
    if (!e.is_directory()) continue;
    Scene s;
    s.name = e.path().filename().string();
    for (const auto& r : fs::directory_iterator(e.path())) {
      if (!r.is_directory()) continue;
      const std::string run = r.path().filename().string();
      if (std::find(kModes.begin(), kModes.end(), run) != kModes.end() || run.rfind("grid-", 0) == 0)
        s.runs[run] = read_vproxq_run(run, r.path());
    }
    s.runs["fcl"] = read_fcl_run(e.path());
    if (fs::exists(e.path() / "pns.json")) {
      std::ifstream in(e.path() / "pns.json");
      s.pns = json::parse(in, nullptr, /*allow_exceptions=*/false);
      if (s.pns.is_discarded()) s.pns = nullptr;
    }
    scenes.push_back(std::move(s));
  }
  auto rank = [](const std::string& n) {
    const auto it = std::find(kPaperOrder.begin(), kPaperOrder.end(), n);
    return static_cast<int>(it - kPaperOrder.begin());
  };
  std::sort(scenes.begin(), scenes.end(), [&](const Scene& a, const Scene& b) {
    return std::make_pair(rank(a.name), a.name) < std::make_pair(rank(b.name), b.name);
  });
  return scenes;
}

/// Mean of an optional per-frame number over the frames where it is present.
struct Mean {
  double sum = 0;
  std::size_t frames = 0;
  void add(const Opt& v) {
    if (!v) return;
    sum += *v;
    ++frames;
  }
  Opt mean() const { return frames ? Opt(sum / static_cast<double>(frames)) : std::nullopt; }
};

/// Means over the frames of a run.
struct Summary {
  bool ok = false;
  std::string error;
  std::size_t frames = 0;
  long long triangles_first = 0, triangles_max = 0, objects_first = 0, objects_max = 0;
  long long static_triangles = 0, static_objects = 0;
  std::array<long long, 3> grid{0, 0, 0};
  double query_ms = 0, load = 0, aabb = 0, voronoi = 0, exact = 0;
  double exact_tests = 0, pns_pairs = 0, feature_pns = 0;
  double fcl_build = 0, fcl_query = 0, fcl_vproxq = 0;
  long long fcl_mismatches = 0;  ///< summed over the frames
  /// Per query: exact tests, mean over the frames where the query ran.
  std::array<Mean, kQueryKinds> tests;
  Mean intra_candidates, intra_voronoi_culled, ccd_vf_tests, ccd_ee_tests, ccd_triangle_pairs,
      ccd_culled_triangles, ccd_limit_hits, ccd_vf_pairs, ccd_ee_pairs;
  /// The query time split per query, mean over all frames of the run (0 on a frame where the
  /// query did not run, so that the three add up to query_ms); absent when it never ran.
  Opt inter_pairs_pd_ms, intra_ms, ccd_ms;
  Opt test_mean(int q) const { return tests[static_cast<std::size_t>(q)].mean(); }
};

Summary summarize(const Run* run) {
  Summary s;
  if (!run) {
    s.error = "not run";
    return s;
  }
  if (run->error) {
    s.error = *run->error;
    return s;
  }
  if (run->frames.empty()) {
    s.error = "no frames";
    return s;
  }
  s.ok = true;
  s.frames = run->frames.size();
  s.triangles_first = run->frames.front().triangles;
  s.objects_first = run->frames.front().objects;
  s.static_triangles = run->frames.front().static_triangles;
  s.static_objects = run->frames.front().static_objects;
  s.grid = run->frames.front().grid;
  const double n = static_cast<double>(s.frames);
  Mean inter_ms, intra_ms, ccd_ms;
  for (const FrameRow& f : run->frames) {
    for (std::size_t q = 0; q < s.tests.size(); ++q) s.tests[q].add(f.tests[q]);
    s.intra_candidates.add(f.intra_candidates);
    s.intra_voronoi_culled.add(f.intra_voronoi_culled);
    s.ccd_vf_tests.add(f.ccd_vf_tests);
    s.ccd_ee_tests.add(f.ccd_ee_tests);
    s.ccd_triangle_pairs.add(f.ccd_triangle_pairs);
    s.ccd_culled_triangles.add(f.ccd_culled_triangles);
    s.ccd_limit_hits.add(f.ccd_limit_hits);
    s.ccd_vf_pairs.add(f.ccd_vf_pairs);
    s.ccd_ee_pairs.add(f.ccd_ee_pairs);
    inter_ms.add(f.inter_pairs_pd_ms());
    intra_ms.add(f.intra_ms());
    ccd_ms.add(f.ccd_ms());
    s.triangles_max = std::max(s.triangles_max, f.triangles);
    s.objects_max = std::max(s.objects_max, f.objects);
    s.query_ms += f.query_ms() / n;
    s.load += f.load / n;
    s.aabb += f.aabb / n;
    s.voronoi += f.voronoi / n;
    s.exact += f.exact / n;
    s.exact_tests += f.exact_tests / n;
    s.pns_pairs += f.pns_pairs / n;
    s.feature_pns += f.feature_pns / n;
    s.fcl_build += f.fcl_build / n;
    s.fcl_query += f.fcl_query / n;
    s.fcl_vproxq += f.fcl_vproxq / n;
    s.fcl_mismatches += f.fcl_mismatches;
  }
  auto over_all_frames = [&](const Mean& m) {
    return m.frames ? Opt(m.sum / n) : std::nullopt;
  };
  s.inter_pairs_pd_ms = over_all_frames(inter_ms);
  s.intra_ms = over_all_frames(intra_ms);
  s.ccd_ms = over_all_frames(ccd_ms);
  return s;
}

const Run* find_run(const Scene& s, const std::string& name) {
  const auto it = s.runs.find(name);
  return it == s.runs.end() ? nullptr : &it->second;
}

std::string fixed(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

/// Thousands separators for counts, as in the paper's figures.
std::string count(double v) {
  std::string digits = fixed(v, 0);
  std::string out;
  const std::size_t neg = digits[0] == '-' ? 1 : 0;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    out += digits[i];
    const std::size_t left = digits.size() - i - 1;
    if (i >= neg && left > 0 && left % 3 == 0) out += ',';
  }
  return out;
}

std::string grid_text(const std::array<long long, 3>& g) {
  if (g[0] == 0) return "-";
  return std::to_string(g[0]) + "×" + std::to_string(g[1]) + "×" + std::to_string(g[2]);
}

/// Markdown-safe one-line reason.
std::string reason(const std::string& e) {
  std::string s = e.substr(0, e.find('\n'));
  for (char& c : s)
    if (c == '|') c = '/';
  return s;
}

std::string ms_cell(const Summary& s) { return s.ok ? fixed(s.query_ms, 1) : "n/a"; }

std::string ratio_cell(const Summary& a, const Summary& b, double Summary::*field) {
  if (!a.ok || !b.ok || !(b.*field > 0)) return "n/a";
  return fixed(a.*field / b.*field, 2);
}

/// A mean count, or "–" when its query did not run.
std::string count_cell(const Opt& v) { return v ? count(*v) : kNotRun; }

/// A mean time in ms, or "–" when its query did not run.
std::string ms_cell(const Opt& v) { return v ? fixed(*v, 1) : kNotRun; }

/// Reduction of query q's exact tests: off's mean over `mode`'s. "–" when the query ran in
/// neither, "n/a" when one of the runs failed, the query ran in only one, or `mode` did none.
std::string reduction_cell(const Summary& off, const Summary& m, int q) {
  if (!off.ok || !m.ok) return "n/a";
  const Opt a = off.test_mean(q), b = m.test_mean(q);
  if (!a && !b) return kNotRun;
  if (!a || !b || !(*b > 0)) return "n/a";
  return fixed(*a / *b, 2);
}

int grid_of(const std::string& run) { return std::stoi(run.substr(5)); }

std::vector<std::string> grid_runs(const Scene& s) {
  std::vector<std::string> out;
  for (const auto& [name, run] : s.runs)
    if (name.rfind("grid-", 0) == 0) out.push_back(name);
  std::sort(out.begin(), out.end(),
            [](const std::string& a, const std::string& b) { return grid_of(a) < grid_of(b); });
  return out;
}

/// The backend(s) the grid sweep ran with, as "--voronoi=cpu" (or "cpu, gpu" if they differ);
/// "cpu" where the runs do not say (results from before settings.voronoi).
std::string grid_modes(const std::vector<Scene>& scenes) {
  std::vector<std::string> modes;
  for (const Scene& s : scenes)
    for (const std::string& g : grid_runs(s)) {
      const Run& r = s.runs.at(g);
      if (r.error) continue;
      const std::string m = r.voronoi.empty() ? "cpu" : r.voronoi;
      if (std::find(modes.begin(), modes.end(), m) == modes.end()) modes.push_back(m);
    }
  if (modes.empty()) modes.push_back("cpu");
  std::string out = "--voronoi=" + modes[0];
  for (std::size_t i = 1; i < modes.size(); ++i) out += ", " + modes[i];
  return out;
}

void write_text(const fs::path& p, const std::string& text) {
  std::ofstream out(p, std::ios::binary | std::ios::trunc);
  out << text;
  if (!out) throw std::runtime_error("cannot write " + p.string());
}

// ---------------------------------------------------------------------------------------------

std::string report_markdown(const std::vector<Scene>& scenes, const std::string& machine) {
  std::ostringstream md;
  md << "# vproxq benchmark report\n\n";
  md << "Written by `vproxq-report` from the runs of `scripts/report.sh`. Times are the mean "
        "over the frames of the proximity query time per frame in milliseconds (vproxq's "
        "`stats.time_ms.total` minus loading the frame), all queries of the run together.\n\n";
  if (!machine.empty()) md << "## Machine\n\n```\n" << machine << "\n```\n\n";

  // Settings actually used, from the results files.
  std::string queries, device;
  int threads = 0;
  for (const Scene& s : scenes)
    for (const auto& [name, run] : s.runs) {
      if (run.error || name == "fcl") continue;
      if (queries.empty()) queries = run.queries;
      if (threads == 0) threads = run.threads;
      if (name == "gpu" && device.empty()) device = run.device;
    }
  md << "Queries: `" << (queries.empty() ? "n/a" : queries) << "`; vproxq threads: "
     << threads << "; GPU device: " << (device.empty() ? "n/a" : device) << ".\n\n";

  md << "## Table 1: average time per frame (ms)\n\n";
  md << "`off`: AABB culling only (Stage I); `cpu`, `gpu`: with the discrete Voronoi diagram "
        "(Stage II) on the CPU or in OpenGL compute shaders. FCL: inter-object distance only "
        "(every object's nearest object), FCL 0.7 BVHModel<OBBRSS> + DynamicAABBTree, rebuilt "
        "every frame, from `vproxq-bench-fcl`. Triangles and objects: frame 0, static geometry "
        "included (its share in the Static column; max over the frames in parentheses where "
        "objects break); grid: the cpu run's voxels per axis.\n\n";
  md << "| Benchmark | Tris | Objects | Static (objects, tris) | Frames | Grid | off (AABB) | "
        "cpu (Voronoi) | gpu (Voronoi) | FCL distance | off / cpu | off / gpu |\n";
  md << "|---|---:|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|\n";
  std::vector<std::string> failures;
  for (const Scene& s : scenes) {
    std::map<std::string, Summary> m;
    for (const std::string& mode : kModes) m[mode] = summarize(find_run(s, mode));
    const Summary fcl = summarize(find_run(s, "fcl"));
    const Summary* any = nullptr;
    for (const std::string& mode : kModes)
      if (m[mode].ok) {
        any = &m[mode];
        break;
      }
    auto range = [](long long first, long long max) {
      return max != first ? count(static_cast<double>(first)) + " (" + count(static_cast<double>(max)) + ")"
                          : count(static_cast<double>(first));
    };
    md << "| " << s.name << " | "
       << (any ? range(any->triangles_first, any->triangles_max) : "n/a") << " | "
       << (any ? range(any->objects_first, any->objects_max) : "n/a") << " | "
       << (any ? std::to_string(any->static_objects) + ", " +
                     count(static_cast<double>(any->static_triangles))
               : "n/a")
       << " | " << (any ? std::to_string(any->frames) : "n/a") << " | "
       << (m["cpu"].ok ? grid_text(m["cpu"].grid) : m["gpu"].ok ? grid_text(m["gpu"].grid) : "n/a")
       << " | " << ms_cell(m["off"]) << " | " << ms_cell(m["cpu"]) << " | " << ms_cell(m["gpu"])
       << " | " << (fcl.ok ? fixed(fcl.fcl_build + fcl.fcl_query, 1) : "n/a") << " | "
       << ratio_cell(m["off"], m["cpu"], &Summary::query_ms) << " | "
       << ratio_cell(m["off"], m["gpu"], &Summary::query_ms) << " |\n";
    for (const std::string& mode : kModes)
      if (!m[mode].ok) failures.push_back(s.name + " " + mode + ": " + reason(m[mode].error));
    if (!fcl.ok) failures.push_back(s.name + " FCL: " + reason(fcl.error));
  }

  md << "\n## Stages (ms per frame) and exact tests (figure 13)\n\n";
  md << "Stage times, mean per frame over all queries of the run (the 2-ring bounds of the "
        "intra-object distance and CCD's swept boxes count as AABB, both Voronoi diagrams and "
        "CCD's voxel culling as Voronoi), and the query time split per query: intra = "
        "`intra_bounds + intra_voronoi + intra_exact`, CCD = the sum of `stats.ccd.time_ms`, "
        "inter + pairs + PD = the rest (inter-object distance, intersecting pairs, penetration "
        "depth). The split is the mean over all frames (0 on a frame where the query did not "
        "run, e.g. CCD on the last frame), so it adds up to the query time; – where the query "
        "did not run.\n\n";
  md << "| Benchmark | mode | AABB | Voronoi | exact | query | inter + pairs + PD | intra | CCD "
        "| object PNS pairs | feature PNS |\n";
  md << "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Scene& s : scenes)
    for (const std::string& mode : kModes) {
      const Summary m = summarize(find_run(s, mode));
      if (!m.ok) {
        md << "| " << s.name << " | " << mode
           << " | n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a |\n";
        continue;
      }
      md << "| " << s.name << " | " << mode << " | " << fixed(m.aabb, 1) << " | "
         << fixed(m.voronoi, 1) << " | " << fixed(m.exact, 1) << " | " << fixed(m.query_ms, 1)
         << " | " << ms_cell(m.inter_pairs_pd_ms) << " | " << ms_cell(m.intra_ms) << " | "
         << ms_cell(m.ccd_ms) << " | " << count(m.pns_pairs) << " | " << count(m.feature_pns)
         << " |\n";
    }

  md << "\n## Exact tests per query (figure 13)\n\n";
  md << "Mean per frame over the frames where the query ran: inter-object exact tests "
        "(`stats.exact_tests`, triangle pairs whose exact distance was computed in Stage III), "
        "intra-object exact tests (`stats.intra_exact_tests`), intersection tests of the "
        "intersecting pairs behind collisions and PD (`stats.intersection_tests`) and CCD "
        "elementary tests (`stats.ccd.elementary_tests`, vertex-face plus edge-edge; frames "
        "with a next frame). Reduction: off / mode. –: the query did not run.\n\n";
  md << "| Benchmark | mode";
  for (int q = 0; q < kQueryKinds; ++q) md << " | " << kQueryTitle[q] << " | reduction";
  md << " |\n|---|---";
  for (int q = 0; q < kQueryKinds; ++q) md << "|---:|---:";
  md << "|\n";
  for (const Scene& s : scenes) {
    const Summary off = summarize(find_run(s, "off"));
    for (const std::string& mode : kModes) {
      const Summary m = summarize(find_run(s, mode));
      md << "| " << s.name << " | " << mode;
      for (int q = 0; q < kQueryKinds; ++q) {
        if (!m.ok) {
          md << " | n/a | n/a";
          continue;
        }
        const Opt v = m.test_mean(q);
        md << " | " << count_cell(v) << " | "
           << (mode == "off" ? (v ? "1" : kNotRun) : reduction_cell(off, m, q));
      }
      md << " |\n";
    }
  }

  if (std::any_of(scenes.begin(), scenes.end(), [](const Scene& s) { return s.pns.is_object(); })) {
    md << "\n## Exact tests against their floor and the paper's PNS (`vproxq-bench-pns`)\n\n";
    md << "Sums over the frames `vproxq-bench-pns` ran (the same frames as the runs above, "
          "Stage II on the CPU at the default grid). *tests*: Stage III's exact tests, whose "
          "bound shrinks to the best distance found so far and which skips pairs whose "
          "separating-axis bound exceeds it; *floor*: the pairs whose boxes (and, "
          "with Stage II, both triangles' D_l) lie within the final answer, which no search "
          "that culls by boxes and D_l alone can skip; *fixed*: the paper's feature-level PNS with "
          "fixed bounds (Stage I's U_i or the 2-ring bound without Stage II, D_u and D_l with "
          "it), what the paper's figure 13 counts. Reduction: off / cpu.\n\n";
    md << "| Benchmark | query | frames | tests off | tests cpu | reduction | floor off | "
          "floor cpu | reduction | fixed off | fixed cpu | reduction |\n"
          "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|\n";
    for (const Scene& s : scenes) {
      if (!s.pns.is_object() || !s.pns.contains("frames") || !s.pns["frames"].is_array()) continue;
      const json& frames = s.pns["frames"];
      for (const char* query : {"inter", "intra"}) {
        std::map<std::string, double> sum;
        for (const json& f : frames)
          for (const char* key : {"tests_off", "tests_cpu", "floor_off", "floor_cpu", "fixed_off", "fixed_cpu"})
            sum[key] += number(object_at(f, query), key);
        auto pair_cells = [&](const std::string& what) {
          const double off = sum[what + "_off"], cpu = sum[what + "_cpu"];
          return count(off) + " | " + count(cpu) + " | " + (cpu > 0 ? fixed(off / cpu, 2) : "n/a");
        };
        md << "| " << s.name << " | " << query << " | " << frames.size() << " | "
           << pair_cells("tests") << " | " << pair_cells("floor") << " | " << pair_cells("fixed")
           << " |\n";
      }
    }
  }

  md << "\n## FCL (inter-object distance only)\n\n";
  md << "`vproxq-bench-fcl` times, per frame, vproxq's inter-object distance without Voronoi "
        "culling and FCL on the same loaded frame (fastest of its repeats), and checks that "
        "they agree.\n\n";
  md << "| Benchmark | frames | FCL build | FCL query | FCL total | vproxq (off, distance) | "
        "FCL / vproxq | distances that disagree |\n";
  md << "|---|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Scene& s : scenes) {
    const Summary f = summarize(find_run(s, "fcl"));
    if (!f.ok) {
      md << "| " << s.name << " | n/a | n/a | n/a | n/a | n/a | n/a | n/a |\n";
      continue;
    }
    md << "| " << s.name << " | " << f.frames << " | " << fixed(f.fcl_build, 1) << " | "
       << fixed(f.fcl_query, 1) << " | " << fixed(f.fcl_build + f.fcl_query, 1) << " | "
       << fixed(f.fcl_vproxq, 1) << " | "
       << (f.fcl_vproxq > 0 ? fixed((f.fcl_build + f.fcl_query) / f.fcl_vproxq, 2) : "n/a")
       << " | " << f.fcl_mismatches << " |\n";
  }

  bool any_grid = false;
  for (const Scene& s : scenes) any_grid = any_grid || !grid_runs(s).empty();
  if (any_grid) {
    md << "\n## Grid resolution (figure 14, `" << grid_modes(scenes) << "`)\n\n";
    md << "| Benchmark | --grid | voxels | Voronoi ms | exact ms | query ms | exact tests |\n";
    md << "|---|---:|---|---:|---:|---:|---:|\n";
    for (const Scene& s : scenes)
      for (const std::string& g : grid_runs(s)) {
        const Summary m = summarize(find_run(s, g));
        if (!m.ok) {
          md << "| " << s.name << " | " << grid_of(g) << " | n/a | n/a | n/a | n/a | n/a |\n";
          failures.push_back(s.name + " " + g + ": " + reason(m.error));
          continue;
        }
        md << "| " << s.name << " | " << grid_of(g) << " | " << grid_text(m.grid) << " | "
           << fixed(m.voronoi, 1) << " | " << fixed(m.exact, 1) << " | " << fixed(m.query_ms, 1)
           << " | " << count(m.exact_tests) << " |\n";
      }
  }

  md << "\n## The paper's Table 1, for comparison\n\n";
  md << "Quoted from the paper (seconds per frame, 2006 hardware: the Voronoi diagram on a GPU "
        "through fragment programs); the ratio column is computed from its two columns. Compare "
        "ratios (AABB only / Voronoi) and the exact-test reduction of figure 13 (5–100×), not "
        "times.\n\n";
  md << "| Benchmark | Tris | Resolution | AABB (s) | Voronoi (s) | AABB / Voronoi |\n";
  md << "|---|---:|---|---:|---:|---:|\n";
  struct PaperRow {
    const char* name;
    const char* tris;
    const char* res;
    double aabb, voronoi;
  };
  const PaperRow paper[] = {{"1. Skirt", "12K", "200×175×45", 1.8, 0.53},
                            {"2. Cloth-Ball", "15K", "190×200×60", 3.8, 0.70},
                            {"3. Bowl", "4.5K", "150×100×30", 1.1, 0.07},
                            {"4. Ramps", "38K", "45×300×40", 13.5, 1.10},
                            {"5. Breaking", "5.5K", "100×100×60", 2.6, 0.12}};
  for (const PaperRow& p : paper)
    md << "| " << p.name << " | " << p.tris << " | " << p.res << " | " << fixed(p.aabb, 2)
       << " | " << fixed(p.voronoi, 2) << " | " << fixed(p.aabb / p.voronoi, 1) << " |\n";

  md << "\n## Figures\n\n![figure 13: exact tests per mode](fig13.png)\n\n"
        "![figure 14: time and exact tests against grid resolution](fig14.png)\n";
  if (!failures.empty()) {
    md << "\n## Runs that did not complete (n/a)\n\n";
    for (const std::string& f : failures) md << "- " << f << "\n";
  }
  return md.str();
}

/// A CSV field: the number, or empty when absent.
std::string csv_opt(const Opt& v) {
  if (!v) return "";
  std::ostringstream o;
  o.precision(10);
  o << *v;
  return o.str();
}

std::string csv_all(const std::vector<Scene>& scenes) {
  std::ostringstream csv;
  csv << "scene,run,frame,objects,triangles,grid_x,grid_y,grid_z,load_ms,aabb_ms,voronoi_ms,"
         "exact_ms,total_ms,query_ms,exact_tests,pns_pairs,feature_pns,fcl_build_ms,"
         "fcl_query_ms,fcl_vproxq_ms,fcl_mismatches";
  for (const char* c : kQueryColumn) csv << ',' << c;
  csv << ",intra_candidates,intra_voronoi_culled,"
         "ccd_vf_tests,ccd_ee_tests,ccd_triangle_pairs,ccd_culled_triangles,ccd_limit_hits,"
         "ccd_vf_pairs,ccd_ee_pairs,intra_bounds_ms,intra_voronoi_ms,intra_exact_ms,"
         "ccd_aabb_ms,ccd_voronoi_ms,ccd_exact_ms,inter_pairs_pd_ms,intra_ms,ccd_ms\n";
  csv.precision(10);
  for (const Scene& s : scenes)
    for (const auto& [name, run] : s.runs)
      for (const FrameRow& f : run.frames) {
        csv << s.name << ',' << name << ',' << f.frame << ',' << f.objects << ',' << f.triangles
            << ',' << f.grid[0] << ',' << f.grid[1] << ',' << f.grid[2] << ',' << f.load << ','
            << f.aabb << ',' << f.voronoi << ',' << f.exact << ',' << f.total << ','
            << (name == "fcl" ? 0.0 : f.query_ms()) << ',' << f.exact_tests << ',' << f.pns_pairs
            << ',' << f.feature_pns << ',' << f.fcl_build << ',' << f.fcl_query << ','
            << f.fcl_vproxq << ',' << f.fcl_mismatches;
        for (const Opt& v : {f.tests[kInter], f.tests[kIntra], f.tests[kIntersect], f.tests[kCcd],
                             f.intra_candidates, f.intra_voronoi_culled, f.ccd_vf_tests,
                             f.ccd_ee_tests, f.ccd_triangle_pairs, f.ccd_culled_triangles,
                             f.ccd_limit_hits, f.ccd_vf_pairs, f.ccd_ee_pairs, f.intra_bounds,
                             f.intra_voronoi, f.intra_exact, f.ccd_aabb, f.ccd_voronoi,
                             f.ccd_exact, f.inter_pairs_pd_ms(), f.intra_ms(), f.ccd_ms()})
          csv << ',' << csv_opt(v);
        csv << '\n';
      }
  return csv.str();
}

std::string csv_summary(const std::vector<Scene>& scenes) {
  std::ostringstream csv;
  csv << "scene,run,status,frames,triangles_first,triangles_max,objects_first,objects_max,"
         "grid_x,grid_y,grid_z,query_ms,load_ms,aabb_ms,voronoi_ms,exact_ms,exact_tests,"
         "pns_pairs,feature_pns,fcl_build_ms,fcl_query_ms,fcl_vproxq_ms,fcl_mismatches";
  for (int q = 0; q < kQueryKinds; ++q) {
    const std::string k = kQueryKey[q];
    csv << ',' << kQueryColumn[q] << ',' << k << "_frames," << k << "_reduction";
  }
  csv << ",intra_candidates,intra_voronoi_culled,ccd_vf_tests,ccd_ee_tests,ccd_triangle_pairs,"
         "ccd_culled_triangles,ccd_limit_hits,ccd_vf_pairs,ccd_ee_pairs,inter_pairs_pd_ms,"
         "intra_ms,ccd_ms\n";
  csv.precision(10);
  for (const Scene& s : scenes) {
    const Summary off = summarize(find_run(s, "off"));
    for (const auto& [name, run] : s.runs) {
      const Summary m = summarize(&run);
      std::string status = m.ok ? "ok" : reason(m.error);
      for (char& c : status)
        if (c == ',' || c == '"') c = ';';
      csv << s.name << ',' << name << ',' << status << ',' << m.frames << ',' << m.triangles_first
          << ',' << m.triangles_max << ',' << m.objects_first << ',' << m.objects_max << ','
          << m.grid[0] << ',' << m.grid[1] << ',' << m.grid[2] << ',' << m.query_ms << ','
          << m.load << ',' << m.aabb << ',' << m.voronoi << ',' << m.exact << ','
          << m.exact_tests << ',' << m.pns_pairs << ',' << m.feature_pns << ',' << m.fcl_build
          << ',' << m.fcl_query << ',' << m.fcl_vproxq << ',' << m.fcl_mismatches;
      // Reductions (off / this run) for the Stage II modes; the grid runs use GRID_MODE's backend.
      const bool voronoi_run = name != "fcl";
      for (int q = 0; q < kQueryKinds; ++q) {
        const Opt v = m.test_mean(q);
        std::string red;
        if (voronoi_run && off.ok && m.ok && v && off.test_mean(q) && *v > 0)
          red = csv_opt(*off.test_mean(q) / *v);
        csv << ',' << csv_opt(v) << ',' << m.tests[static_cast<std::size_t>(q)].frames << ','
            << red;
      }
      for (const Opt& v : {m.intra_candidates.mean(), m.intra_voronoi_culled.mean(),
                           m.ccd_vf_tests.mean(), m.ccd_ee_tests.mean(),
                           m.ccd_triangle_pairs.mean(), m.ccd_culled_triangles.mean(),
                           m.ccd_limit_hits.mean(), m.ccd_vf_pairs.mean(), m.ccd_ee_pairs.mean(),
                           m.inter_pairs_pd_ms, m.intra_ms, m.ccd_ms})
        csv << ',' << csv_opt(v);
      csv << '\n';
    }
  }
  return csv.str();
}

/// fig13.dat: one row per scene, mean exact tests per query and mode (columns 2-4: inter
/// off/cpu/gpu, 5-7 intra, 8-10 intersection, 11-13 CCD; "NaN" where the run is missing, the
/// query did not run, or 0 tests, which a log scale cannot show). fig13.gp draws one panel per
/// query (a clustered histogram of the modes per scene); a query with no data anywhere gets an
/// empty panel that says so.
void write_fig13(const std::vector<Scene>& scenes, const fs::path& out) {
  std::ostringstream dat;
  dat << "# scene";
  for (int q = 0; q < kQueryKinds; ++q)
    for (const std::string& mode : kModes) dat << ' ' << kQueryKey[q] << '_' << mode;
  dat << " (mean exact tests per frame)\n";
  std::array<double, kQueryKinds> top{};  ///< largest value shown per query (0: none)
  for (const Scene& s : scenes) {
    dat << s.name;
    std::vector<Summary> m;
    for (const std::string& mode : kModes) m.push_back(summarize(find_run(s, mode)));
    for (int q = 0; q < kQueryKinds; ++q)
      for (const Summary& r : m) {
        const Opt v = r.ok ? r.test_mean(q) : std::nullopt;
        const bool shown = v && *v > 0;
        if (shown) top[static_cast<std::size_t>(q)] = std::max(top[static_cast<std::size_t>(q)], *v);
        dat << ' ' << (shown ? fixed(*v, 1) : "NaN");
      }
    dat << '\n';
  }
  write_text(out / "fig13.dat", dat.str());
  std::ostringstream gp;
  gp << "# gnuplot fig13.gp (in this folder) writes fig13.png: the paper's figure 13, one panel "
        "per query.\n"
        "set terminal pngcairo size 1200,900 noenhanced font ',11'\n"
        "set output 'fig13.png'\n"
        "set datafile missing 'NaN'\n"
        "set style data histograms\n"
        "set style histogram clustered gap 1\n"
        "set style fill solid 0.8 border -1\n"
        "set grid ytics\n"
        "set multiplot layout 2,2 title 'Exact tests per frame: AABB only vs. Voronoi culling "
        "(log scale)'\n";
  for (int q = 0; q < kQueryKinds; ++q) {
    const int col = 2 + 3 * q;
    gp << "set title '" << kQueryTitle[q] << "'\n";
    const double max = top[static_cast<std::size_t>(q)];
    if (max > 0) {
      // A decade of room above the tallest bar.
      gp << "set logscale y\nset yrange [1:" << fixed(std::max(10.0, max * 10), 0)
         << "]\nset ylabel 'mean per frame'\nset xtics\nset ytics\nset key below horizontal\n"
            "plot 'fig13.dat' using " << col << ":xtic(1) title 'off (AABB)', '' using "
         << col + 1 << " title 'cpu (Voronoi)', '' using " << col + 2 << " title 'gpu (Voronoi)'\n";
    } else {
      gp << "unset logscale y\nset yrange [0:1]\nunset ylabel\nunset xtics\nunset ytics\nunset key\n"
            "set label 1 'not run' at graph 0.5, graph 0.5 center\n"
            "plot [0:1] NaN notitle\n"
            "unset label 1\n";
    }
  }
  gp << "unset multiplot\n";
  write_text(out / "fig13.gp", gp.str());
}

/// fig14.dat: one block per scene with a grid sweep (gnuplot `index`), a row per grid.
void write_fig14(const std::vector<Scene>& scenes, const fs::path& out) {
  std::ostringstream dat, plot_time, plot_tests;
  dat << "# grid voronoi_ms exact_ms query_ms exact_tests (mean per frame), one block per scene\n";
  int index = 0;
  for (const Scene& s : scenes) {
    const auto runs = grid_runs(s);
    if (runs.empty()) continue;
    dat << "# " << s.name << '\n';
    for (const std::string& g : runs) {
      const Summary m = summarize(find_run(s, g));
      if (!m.ok) continue;
      dat << grid_of(g) << ' ' << fixed(m.voronoi, 3) << ' ' << fixed(m.exact, 3) << ' '
          << fixed(m.query_ms, 3) << ' ' << fixed(m.exact_tests, 1) << '\n';
    }
    dat << "\n\n";
    const std::string i = std::to_string(index++);
    plot_time << (plot_time.tellp() > 0 ? ", \\\n     " : "") << "'fig14.dat' index " << i
              << " using 1:4 with linespoints title '" << s.name << " query', '' index " << i
              << " using 1:2 with linespoints dashtype 2 title '" << s.name << " Voronoi'";
    plot_tests << (plot_tests.tellp() > 0 ? ", \\\n     " : "") << "'fig14.dat' index " << i
               << " using 1:5 with linespoints title '" << s.name << "'";
  }
  write_text(out / "fig14.dat", dat.str());
  std::string gp =
      "# gnuplot fig14.gp (in this folder) writes fig14.png: the paper's figure 14.\n"
      "set terminal pngcairo size 1100,480 noenhanced font ',11'\n"
      "set output 'fig14.png'\n";
  if (index == 0) {
    gp += "set title 'no grid sweep was run'\nunset border\nunset tics\nplot [0:1][0:1] NaN notitle\n";
  } else {
    gp += "set multiplot layout 1,2 title 'Grid resolution (" + grid_modes(scenes) + ")'\n"
          "set xlabel '--grid (voxels along the longest axis)'\n"
          "set grid\nset key top left\n"
          "set ylabel 'ms per frame'\n"
          "set title 'time'\n"
          "plot " + plot_time.str() + "\n"
          "set logscale y\n"
          "set ylabel 'mean exact tests per frame (log scale)'\n"
          "set title 'exact tests'\n"
          "set key top right\n"
          "plot " + plot_tests.str() + "\n"
          "unset multiplot\n";
  }
  write_text(out / "fig14.gp", gp);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"vproxq-report: aggregates scripts/report.sh's benchmark runs into report.md "
               "(a table like the paper's Table 1), results.csv, summary.csv and gnuplot scripts "
               "for the paper's figures 13 and 14."};
  fs::path runs, out, machine;
  app.add_option("--runs", runs, "folder with one subfolder per scene (see the source header)")
      ->required()
      ->check(CLI::ExistingDirectory);
  app.add_option("--out", out, "output folder (created if missing)")->required();
  app.add_option("--machine", machine, "text file describing the machine, quoted in the report")
      ->check(CLI::ExistingFile);
  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    return app.exit(e) == 0 ? 0 : 2;
  }
  try {
    const std::vector<Scene> scenes = read_scenes(runs);
    if (scenes.empty()) {
      std::cerr << "vproxq-report: error: no scene folders in " << runs << "\n";
      return 3;
    }
    fs::create_directories(out);
    write_text(out / "report.md", report_markdown(scenes, machine.empty() ? "" : slurp(machine)));
    write_text(out / "results.csv", csv_all(scenes));
    write_text(out / "summary.csv", csv_summary(scenes));
    write_fig13(scenes, out);
    write_fig14(scenes, out);
    std::printf("vproxq-report: %zu scene(s); wrote %s\n", scenes.size(),
                (out / "report.md").string().c_str());
    return 0;
  } catch (const std::exception& e) {
    std::cerr << "vproxq-report: error: " << e.what() << "\n";
    return 4;
  }
}
