// vproxq-report (bench/report/) on a small input: real vproxq runs of two tiny sample scenes,
// a failed run and an FCL file. The report's numbers must be the means of the inputs, missing
// runs must show as n/a with their reason, and the CSV must hold every frame of every run.
#include "support/cli.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <array>
#include <fstream>
#include <map>
#include <optional>
#include <sstream>
#include <vector>

namespace vproxq {
namespace {

namespace fs = std::filesystem;
using test::quote;
using test::run_command;
using test::ScratchDir;
using test::slurp;

const fs::path kSamples = VPROXQ_SAMPLE_SCENES_DIR;

std::size_t count_lines(const std::string& s) {
  return static_cast<std::size_t>(std::count(s.begin(), s.end(), '\n'));
}

/// Thousands separators, no decimals: the report's counts.
std::string count_text(double v) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.0f", v);
  std::string digits = buf, out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    out += digits[i];
    const std::size_t left = digits.size() - i - 1;
    if (left > 0 && left % 3 == 0) out += ',';
  }
  return out;
}

std::string fixed_text(double v, int digits) {
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.*f", digits, v);
  return buf;
}

using Opt = std::optional<double>;
using nlohmann::json;

/// The numbers a run's row should show, computed here from its results.json: per query the
/// mean exact tests over the frames where it ran (inter, intra, intersection, CCD), and the
/// query time split, mean over all frames.
struct Expected {
  std::array<Opt, 4> tests;
  std::array<std::size_t, 4> frames{};
  Opt inter_ms, intra_ms, ccd_ms;
};

Expected expected_from(const fs::path& results) {
  std::ifstream in(results);
  const json j = json::parse(in);
  std::array<double, 4> sum{};
  Expected e;
  double inter_ms = 0, intra_ms = 0, ccd_ms = 0;
  bool inter_ran = false, intra_ran = false, ccd_ran = false;
  for (const json& f : j["frames"]) {
    const json st = f.value("stats", json::object());
    const json t = st.value("time_ms", json::object());
    auto add = [&](std::size_t q, const json& v) {
      sum[q] += v.get<double>();
      ++e.frames[q];
    };
    const bool inter = f.contains("distance") && f["distance"].contains("inter");
    if (inter) add(0, st["exact_tests"]);
    if (st.contains("intra_exact_tests")) add(1, st["intra_exact_tests"]);
    if (st.contains("intersection_tests")) add(2, st["intersection_tests"]);
    if (st.contains("ccd")) add(3, st["ccd"]["elementary_tests"]);
    double intra = 0, ccd = 0;
    if (t.contains("intra_bounds")) {
      intra = t["intra_bounds"].get<double>() + t["intra_voronoi"].get<double>() +
              t["intra_exact"].get<double>();
      intra_ran = true;
    }
    if (st.contains("ccd")) {
      const json& c = st["ccd"]["time_ms"];
      ccd = c["aabb"].get<double>() + c["voronoi"].get<double>() + c["exact"].get<double>();
      ccd_ran = true;
    }
    if (inter || st.contains("intersection_tests")) {
      inter_ms += t["total"].get<double>() - t["load"].get<double>() - intra - ccd;
      inter_ran = true;
    }
    intra_ms += intra;
    ccd_ms += ccd;
  }
  const double n = static_cast<double>(j["frames"].size());
  for (std::size_t q = 0; q < 4; ++q)
    if (e.frames[q]) e.tests[q] = sum[q] / static_cast<double>(e.frames[q]);
  if (inter_ran) e.inter_ms = inter_ms / n;
  if (intra_ran) e.intra_ms = intra_ms / n;
  if (ccd_ran) e.ccd_ms = ccd_ms / n;
  return e;
}

/// The line of `md` after `heading` that starts with `prefix`.
std::string row_after(const std::string& md, const std::string& heading, const std::string& prefix) {
  const auto h = md.find(heading);
  if (h == std::string::npos) return "(no " + heading + ")";
  const auto row = md.find("\n" + prefix, h);
  if (row == std::string::npos) return "(no row " + prefix + ")";
  return md.substr(row + 1, md.find('\n', row + 1) - row - 1);
}

std::vector<std::string> split(const std::string& s, char sep) {
  std::vector<std::string> out(1);
  for (char c : s) {
    if (c == sep) out.emplace_back();
    else out.back() += c;
  }
  return out;
}

/// CSV rows as maps from column name to field.
std::vector<std::map<std::string, std::string>> read_csv(const fs::path& file) {
  std::istringstream in(slurp(file));
  std::string line;
  std::getline(in, line);
  const auto header = split(line, ',');
  std::vector<std::map<std::string, std::string>> rows;
  while (std::getline(in, line)) {
    const auto fields = split(line, ',');
    EXPECT_EQ(fields.size(), header.size()) << line;
    std::map<std::string, std::string> row;
    for (std::size_t i = 0; i < header.size() && i < fields.size(); ++i) row[header[i]] = fields[i];
    rows.push_back(row);
  }
  return rows;
}

const char* const kTestColumn[4] = {"inter_exact_tests", "intra_exact_tests", "intersection_tests",
                                    "ccd_elementary_tests"};
const char* const kQueryKey[4] = {"inter", "intra", "intersection", "ccd"};

TEST(Report, AggregatesRunsIntoTablesCsvAndGnuplotScripts) {
  ScratchDir dir;
  const fs::path runs = dir / "runs";
  // Scene folders named like the paper's benchmarks, so the table follows its order. bowl runs
  // every query; breaking the distance only (so no CCD stats: "–").
  struct SceneRun {
    const char* name;
    const char* sample;
    const char* queries;
  };
  const SceneRun scenes[] = {{"breaking", "breaking-tiny", "distance"},
                             {"bowl", "bowl-tiny", "distance,ccd,pd"}};
  for (const SceneRun& sc : scenes) {
    for (const char* mode : {"off", "cpu"}) {
      const auto r = run_command(std::string(VPROXQ_BINARY) + " " +
                                 quote(kSamples / sc.sample / "scene.json") +
                                 " -q --threads 2 --queries=" + sc.queries +
                                 " --voronoi=" + mode + " -o " + quote(runs / sc.name / mode));
      ASSERT_EQ(r.exit_code, 0) << r.output;
    }
    dir.write(std::string("runs/") + sc.name + "/gpu/error.txt", "no EGL display here\n");
  }
  // A run whose frames lack the per-query stats (a frame without "stats" at all, one with
  // only the always-present keys and no "distance"): every per-query number is "–".
  dir.write("runs/funnel/off/results.json",
            R"({"tool": "vproxq", "queries": ["pd"], "settings": {"threads": 2}, "frames": [
                {"frame": 0, "objects": [{"id": 0, "triangles": 10}],
                 "stats": {"time_ms": {"load": 1.0, "total": 3.0}, "exact_tests": 7}},
                {"frame": 1, "objects": [{"id": 0, "triangles": 10}]}]})");
  dir.write("runs/bowl/fcl.json",
            R"({"fcl_version": "0.7.0", "threads": 2, "fcl_threads": 2, "repeat": 1, "frames": [
                {"frame": 0, "objects": 4, "triangles": 840, "touching": 0, "vproxq_ms": 2.0,
                 "fcl_build_ms": 1.0, "fcl_query_ms": 3.0, "mismatches": 0},
                {"frame": 1, "objects": 4, "triangles": 840, "touching": 0, "vproxq_ms": 4.0,
                 "fcl_build_ms": 1.0, "fcl_query_ms": 5.0, "mismatches": 0}]})");
  dir.write("runs/breaking/fcl-error.txt", "vproxq-bench-fcl failed (exit status 3): test\n");

  const auto r = run_command(std::string(VPROXQ_REPORT_BINARY) + " --runs " + quote(runs) +
                             " --out " + quote(dir / "report"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string md = slurp(dir / "report" / "report.md");

  // Paper order: bowl (3), funnel (4), breaking (5).
  const auto bowl = md.find("| bowl |"), funnel = md.find("| funnel |"),
             breaking = md.find("| breaking |");
  ASSERT_NE(bowl, std::string::npos) << md;
  ASSERT_NE(funnel, std::string::npos) << md;
  ASSERT_NE(breaking, std::string::npos) << md;
  EXPECT_LT(bowl, funnel);
  EXPECT_LT(funnel, breaking);
  // scripts/report.sh prints Table 1 up to the next heading, "## Stages".
  EXPECT_NE(md.find("## Stages"), std::string::npos);
  // FCL: mean of build + query = (4 + 6) / 2 = 5.0 ms, over vproxq's mean 3.0 ms.
  EXPECT_NE(md.find("| bowl | 2 | 1.0 | 4.0 | 5.0 | 3.0 | 1.67 | 0 |"), std::string::npos) << md;
  // Failed runs are n/a, with their reasons listed.
  EXPECT_NE(md.find("breaking gpu: no EGL display here"), std::string::npos) << md;
  EXPECT_NE(md.find("breaking FCL: vproxq-bench-fcl failed (exit status 3): test"),
            std::string::npos) << md;

  // Per query exact tests, reductions and time split: computed here from the results files.
  const std::string kTests = "## Exact tests per query", kStages = "## Stages";
  auto cell = [](const Opt& v) { return v ? count_text(*v) : std::string("–"); };
  auto ms = [](const Opt& v) { return v ? fixed_text(*v, 1) : std::string("–"); };
  for (const SceneRun& sc : scenes) {
    const Expected off = expected_from(runs / sc.name / "off" / "results.json");
    for (const char* mode : {"off", "cpu"}) {
      const Expected e = expected_from(runs / sc.name / mode / "results.json");
      std::string want = std::string("| ") + sc.name + " | " + mode;
      for (std::size_t q = 0; q < 4; ++q) {
        std::string red;
        if (std::string(mode) == "off") red = e.tests[q] ? "1" : "–";
        else if (!off.tests[q] && !e.tests[q]) red = "–";
        else if (!off.tests[q] || !e.tests[q] || !(*e.tests[q] > 0)) red = "n/a";
        else red = fixed_text(*off.tests[q] / *e.tests[q], 2);
        want += " | " + cell(e.tests[q]) + " | " + red;
      }
      want += " |";
      EXPECT_EQ(row_after(md, kTests, std::string("| ") + sc.name + " | " + mode + " |"), want);
      const std::string stages =
          row_after(md, kStages, std::string("| ") + sc.name + " | " + mode + " |");
      EXPECT_NE(stages.find(" | " + ms(e.inter_ms) + " | " + ms(e.intra_ms) + " | " +
                            ms(e.ccd_ms) + " | "),
                std::string::npos) << stages;
      // What ran: distance (inter, intra, intersections) everywhere, CCD only in bowl.
      EXPECT_TRUE(e.tests[0] && e.tests[1] && e.tests[2]);
      EXPECT_EQ(e.tests[3].has_value(), std::string(sc.name) == "bowl");
    }
    EXPECT_EQ(row_after(md, kTests, std::string("| ") + sc.name + " | gpu |"),
              std::string("| ") + sc.name + " | gpu | n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a |");
  }
  // Absent keys: "–", never a number; a missing run: n/a.
  EXPECT_EQ(row_after(md, kTests, "| funnel | off |"),
            "| funnel | off | – | – | – | – | – | – | – | – |");
  EXPECT_EQ(row_after(md, kStages, "| funnel | off |"),
            "| funnel | off | 0.0 | 0.0 | 0.0 | 1.0 | – | – | – | 0 | 0 |");
  EXPECT_EQ(row_after(md, kTests, "| funnel | cpu |"),
            "| funnel | cpu | n/a | n/a | n/a | n/a | n/a | n/a | n/a | n/a |");

  // results.csv: a header and one row per frame of each run (4 frames per tiny scene, 2
  // vproxq runs each, 2 hand-written frames, plus 2 FCL frames); the per-query numbers of
  // each frame, empty where absent.
  const std::string csv = slurp(dir / "report" / "results.csv");
  EXPECT_EQ(count_lines(csv), 1u + 2 * 2 * 4 + 2 + 2);
  EXPECT_EQ(csv.rfind("scene,run,frame,", 0), 0u);
  const auto rows = read_csv(dir / "report" / "results.csv");
  std::size_t checked = 0;
  for (const auto& row : rows) {
    if (row.at("run") == "fcl") continue;
    const fs::path file = runs / row.at("scene") / row.at("run") / "results.json";
    std::ifstream in(file);
    const json j = json::parse(in);
    const json* frame = nullptr;
    for (const json& f : j["frames"])
      if (std::to_string(f["frame"].get<int>()) == row.at("frame")) frame = &f;
    ASSERT_NE(frame, nullptr) << file;
    const json st = frame->contains("stats") ? (*frame)["stats"] : json::object();
    const bool inter = frame->contains("distance") && (*frame)["distance"].contains("inter");
    const std::array<std::optional<json>, 4> want = {
        inter ? std::optional<json>(st["exact_tests"]) : std::nullopt,
        st.contains("intra_exact_tests") ? std::optional<json>(st["intra_exact_tests"]) : std::nullopt,
        st.contains("intersection_tests") ? std::optional<json>(st["intersection_tests"]) : std::nullopt,
        st.contains("ccd") ? std::optional<json>(st["ccd"]["elementary_tests"]) : std::nullopt};
    for (std::size_t q = 0; q < 4; ++q) {
      const std::string got = row.at(kTestColumn[q]);
      if (want[q]) EXPECT_EQ(got, std::to_string(want[q]->get<long long>())) << kTestColumn[q];
      else EXPECT_EQ(got, "") << kTestColumn[q] << " " << row.at("scene");
    }
    ++checked;
  }
  EXPECT_EQ(checked, 2u * 2 * 4 + 2);

  // summary.csv: per run, the per-query means, frames where the query ran and reductions.
  const std::string summary = slurp(dir / "report" / "summary.csv");
  EXPECT_NE(summary.find("breaking,gpu,no EGL display here"), std::string::npos);
  const auto sum_rows = read_csv(dir / "report" / "summary.csv");
  for (const auto& row : sum_rows) {
    const std::string scene = row.at("scene"), run = row.at("run");
    if (run == "fcl" || row.at("status") != "ok") {
      for (std::size_t q = 0; q < 4; ++q) EXPECT_EQ(row.at(kTestColumn[q]), "") << scene << run;
      continue;
    }
    const Expected e = expected_from(runs / scene / run / "results.json");
    for (std::size_t q = 0; q < 4; ++q) {
      EXPECT_EQ(row.at(std::string(kQueryKey[q]) + "_frames"), std::to_string(e.frames[q]));
      if (e.tests[q]) {
        EXPECT_NEAR(std::stod(row.at(kTestColumn[q])), *e.tests[q], 1e-6 * (1 + *e.tests[q]))
            << scene << " " << run << " " << kTestColumn[q];
      } else {
        EXPECT_EQ(row.at(kTestColumn[q]), "") << scene << " " << run << " " << kTestColumn[q];
        EXPECT_EQ(row.at(std::string(kQueryKey[q]) + "_reduction"), "");
      }
    }
  }

  // Gnuplot inputs: fig13 has a row per scene with off/cpu/gpu for each of the four queries
  // and a panel per query; fig14 says no sweep ran.
  const std::string fig13 = slurp(dir / "report" / "fig13.dat");
  for (const char* name : {"bowl", "breaking", "funnel"}) {
    const auto at = fig13.find(std::string("\n") + name + " ");
    ASSERT_NE(at, std::string::npos) << fig13;
    EXPECT_EQ(split(fig13.substr(at + 1, fig13.find('\n', at + 1) - at - 1), ' ').size(), 13u);
  }
  EXPECT_NE(fig13.find("\nfunnel NaN NaN NaN NaN NaN NaN NaN NaN NaN NaN NaN NaN\n"),
            std::string::npos) << fig13;
  const std::string gp13 = slurp(dir / "report" / "fig13.gp");
  EXPECT_NE(gp13.find("set output 'fig13.png'"), std::string::npos);
  EXPECT_NE(gp13.find("set multiplot layout 2,2"), std::string::npos);
  for (const char* title : {"inter-object exact tests", "intra-object exact tests",
                            "intersection tests", "CCD elementary tests"})
    EXPECT_NE(gp13.find(std::string("set title '") + title + "'"), std::string::npos) << title;
  EXPECT_NE(slurp(dir / "report" / "fig14.gp").find("no grid sweep"), std::string::npos);
}

TEST(Report, EmptyRunsFolderIsAnError) {
  ScratchDir dir;
  std::filesystem::create_directories(dir / "runs");
  const auto r = run_command(std::string(VPROXQ_REPORT_BINARY) + " --runs " +
                             quote(dir / "runs") + " --out " + quote(dir / "report"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
}

}  // namespace
}  // namespace vproxq
