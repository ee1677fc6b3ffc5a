// vproxq-report: aggregates the benchmark runs of scripts/report.sh into a report like the
// paper's Table 1 and figures 13 and 14 (section 6.2).
//
//   vproxq-report --runs bench-out/report/runs --out bench-out/report [--machine FILE]
//
// Input, one folder per scene under --runs (scene order: the paper's, then by name):
//   <scene>/off/results.json, cpu/results.json, gpu/results.json   vproxq -o, per Stage II mode
//   <scene>/grid-<N>/results.json                                    vproxq --voronoi=cpu --grid N
//   <scene>/fcl.json                                                 vproxq-bench-fcl --json
//   <scene>/<run>/error.txt or <scene>/fcl-error.txt                 why a run failed ("n/a")
// Output in --out: report.md (the tables), results.csv (every per-frame number of every run),
// summary.csv (the per-run averages behind the tables), fig13.dat/.gp and fig14.dat/.gp (gnuplot
// scripts writing fig13.png and fig14.png; scripts/report.sh runs them). Times are the mean
// per frame of the query time: vproxq's total minus loading the frame.
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

/// One frame of one run, the numbers of results.json's "stats" (or of vproxq-bench-fcl).
struct FrameRow {
  int frame = 0;
  long long objects = 0, triangles = 0;        ///< all objects, static ones included
  long long static_objects = 0, static_triangles = 0;
  std::array<long long, 3> grid{0, 0, 0};
  double load = 0, aabb = 0, voronoi = 0, exact = 0, total = 0;
  double exact_tests = 0, pns_pairs = 0, feature_pns = 0;
  double fcl_build = 0, fcl_query = 0, fcl_vproxq = 0;
  long long fcl_mismatches = 0;  ///< per-object distances where FCL and vproxq disagree
  double query_ms() const { return total - load; }
};

struct Run {
  std::string name;             ///< off, cpu, gpu, grid-N, fcl
  std::optional<std::string> error;
  std::vector<FrameRow> frames;
  std::string device;
  std::string queries;
  int threads = 0;
  int grid_setting = 0;  ///< --grid of a grid-N run
};

struct Scene {
  std::string name;
  std::map<std::string, Run> runs;
};

std::string slurp(const fs::path& p) {
  std::ifstream in(p, std::ios::binary);
  std::string s((std::istreambuf_iterator<char>(in)), {});
  while (!s.empty() && (s.back() == '\n' || s.back() == '\r')) s.pop_back();
  return s;
}

double number(const json& j, const char* key) {
  return j.contains(key) && j[key].is_number() ? j[key].get<double>() : 0.0;
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
    const json& st = f.value("stats", json::object());
    const json& t = st.value("time_ms", json::object());
    r.load = number(t, "load");
    r.aabb = number(t, "aabb");
    r.voronoi = number(t, "voronoi");
    r.exact = number(t, "exact");
    r.total = number(t, "total");
    r.exact_tests = number(st, "exact_tests");
    r.pns_pairs = number(st, "pns_pairs");
    r.feature_pns = number(st, "feature_pns");
    if (st.contains("voronoi") && st["voronoi"].contains("grid"))
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
  for (const FrameRow& f : run->frames) {
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

int grid_of(const std::string& run) { return std::stoi(run.substr(5)); }

std::vector<std::string> grid_runs(const Scene& s) {
  std::vector<std::string> out;
  for (const auto& [name, run] : s.runs)
    if (name.rfind("grid-", 0) == 0) out.push_back(name);
  std::sort(out.begin(), out.end(),
            [](const std::string& a, const std::string& b) { return grid_of(a) < grid_of(b); });
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
  md << "Exact tests: triangle pairs whose exact distance was computed (Stage III), mean per "
        "frame. Reduction: off / Voronoi.\n\n";
  md << "| Benchmark | mode | AABB | Voronoi | exact | query | exact tests | object PNS pairs "
        "| feature PNS | reduction |\n";
  md << "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|\n";
  for (const Scene& s : scenes) {
    const Summary off = summarize(find_run(s, "off"));
    for (const std::string& mode : kModes) {
      const Summary m = summarize(find_run(s, mode));
      if (!m.ok) {
        md << "| " << s.name << " | " << mode << " | n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a |\n";
        continue;
      }
      md << "| " << s.name << " | " << mode << " | " << fixed(m.aabb, 1) << " | "
         << fixed(m.voronoi, 1) << " | " << fixed(m.exact, 1) << " | " << fixed(m.query_ms, 1)
         << " | " << count(m.exact_tests) << " | " << count(m.pns_pairs) << " | "
         << count(m.feature_pns) << " | "
         << (mode == "off" ? "1" : ratio_cell(off, m, &Summary::exact_tests)) << " |\n";
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
    md << "\n## Grid resolution (figure 14, `--voronoi=cpu`)\n\n";
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

std::string csv_all(const std::vector<Scene>& scenes) {
  std::ostringstream csv;
  csv << "scene,run,frame,objects,triangles,grid_x,grid_y,grid_z,load_ms,aabb_ms,voronoi_ms,"
         "exact_ms,total_ms,query_ms,exact_tests,pns_pairs,feature_pns,fcl_build_ms,"
         "fcl_query_ms,fcl_vproxq_ms,fcl_mismatches\n";
  csv.precision(10);
  for (const Scene& s : scenes)
    for (const auto& [name, run] : s.runs)
      for (const FrameRow& f : run.frames)
        csv << s.name << ',' << name << ',' << f.frame << ',' << f.objects << ',' << f.triangles
            << ',' << f.grid[0] << ',' << f.grid[1] << ',' << f.grid[2] << ',' << f.load << ','
            << f.aabb << ',' << f.voronoi << ',' << f.exact << ',' << f.total << ','
            << (name == "fcl" ? 0.0 : f.query_ms()) << ',' << f.exact_tests << ',' << f.pns_pairs
            << ',' << f.feature_pns << ',' << f.fcl_build << ',' << f.fcl_query << ','
            << f.fcl_vproxq << ',' << f.fcl_mismatches << '\n';
  return csv.str();
}

std::string csv_summary(const std::vector<Scene>& scenes) {
  std::ostringstream csv;
  csv << "scene,run,status,frames,triangles_first,triangles_max,objects_first,objects_max,"
         "grid_x,grid_y,grid_z,query_ms,load_ms,aabb_ms,voronoi_ms,exact_ms,exact_tests,"
         "pns_pairs,feature_pns,fcl_build_ms,fcl_query_ms,fcl_vproxq_ms,fcl_mismatches\n";
  csv.precision(10);
  for (const Scene& s : scenes)
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
          << ',' << m.fcl_query << ',' << m.fcl_vproxq << ',' << m.fcl_mismatches << '\n';
    }
  return csv.str();
}

/// fig13.dat: one row per scene, mean exact tests per mode ("NaN" where the run is missing,
/// or 0 tests, which a log scale cannot show).
void write_fig13(const std::vector<Scene>& scenes, const fs::path& out) {
  std::ostringstream dat;
  dat << "# scene off cpu gpu (mean exact tests per frame)\n";
  for (const Scene& s : scenes) {
    dat << s.name;
    for (const std::string& mode : kModes) {
      const Summary m = summarize(find_run(s, mode));
      dat << ' ' << (m.ok && m.exact_tests > 0 ? fixed(m.exact_tests, 1) : "NaN");
    }
    dat << '\n';
  }
  write_text(out / "fig13.dat", dat.str());
  write_text(out / "fig13.gp",
             "# gnuplot fig13.gp (in this folder) writes fig13.png: the paper's figure 13.\n"
             "set terminal pngcairo size 900,540 noenhanced font ',11'\n"
             "set output 'fig13.png'\n"
             "set title 'Exact triangle-pair tests per frame: AABB only vs. Voronoi culling'\n"
             "set datafile missing 'NaN'\n"
             "set style data histograms\n"
             "set style histogram clustered gap 1\n"
             "set style fill solid 0.8 border -1\n"
             "set logscale y\n"
             "set yrange [1:*]\n"
             "set ylabel 'mean exact tests per frame (log scale)'\n"
             "set grid ytics\n"
             "set key top left\n"
             "plot 'fig13.dat' using 2:xtic(1) title 'off (AABB)', '' using 3 title 'cpu "
             "(Voronoi)', '' using 4 title 'gpu (Voronoi)'\n");
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
    gp += "set multiplot layout 1,2 title 'Grid resolution (--voronoi=cpu)'\n"
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
