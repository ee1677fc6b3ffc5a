// vproxq-report (bench/report/) on a small input: real vproxq runs of two tiny sample scenes,
// a failed run and an FCL file. The report's numbers must be the means of the inputs, missing
// runs must show as n/a with their reason, and the CSV must hold every frame of every run.
#include "support/cli.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <sstream>

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

/// Mean of stats.exact_tests over the frames of a results.json, formatted like the report
/// (thousands separators, no decimals).
std::string mean_exact_tests(const fs::path& results) {
  std::ifstream in(results);
  const auto j = nlohmann::json::parse(in);
  double sum = 0;
  for (const auto& f : j["frames"]) sum += f["stats"]["exact_tests"].get<double>();
  char buf[64];
  std::snprintf(buf, sizeof buf, "%.0f", sum / static_cast<double>(j["frames"].size()));
  std::string digits = buf, out;
  for (std::size_t i = 0; i < digits.size(); ++i) {
    out += digits[i];
    const std::size_t left = digits.size() - i - 1;
    if (left > 0 && left % 3 == 0) out += ',';
  }
  return out;
}

TEST(Report, AggregatesRunsIntoTablesCsvAndGnuplotScripts) {
  ScratchDir dir;
  const fs::path runs = dir / "runs";
  // Scene folders named like the paper's benchmarks, so the table follows its order.
  const std::pair<const char*, const char*> scenes[] = {{"breaking", "breaking-tiny"},
                                                        {"bowl", "bowl-tiny"}};
  for (const auto& [name, sample] : scenes) {
    for (const char* mode : {"off", "cpu"}) {
      const auto r = run_command(std::string(VPROXQ_BINARY) + " " +
                                 quote(kSamples / sample / "scene.json") +
                                 " -q --threads 2 --voronoi=" + mode + " -o " +
                                 quote(runs / name / mode));
      ASSERT_EQ(r.exit_code, 0) << r.output;
    }
    dir.write(std::string("runs/") + name + "/gpu/error.txt", "no EGL display here\n");
  }
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

  // Paper order: bowl (3) before breaking (5).
  const auto bowl = md.find("| bowl |"), breaking = md.find("| breaking |");
  ASSERT_NE(bowl, std::string::npos) << md;
  ASSERT_NE(breaking, std::string::npos) << md;
  EXPECT_LT(bowl, breaking);
  // FCL: mean of build + query = (4 + 6) / 2 = 5.0 ms, over vproxq's mean 3.0 ms.
  EXPECT_NE(md.find("| bowl | 2 | 1.0 | 4.0 | 5.0 | 3.0 | 1.67 | 0 |"), std::string::npos) << md;
  // Failed runs are n/a, with their reasons listed.
  EXPECT_NE(md.find("breaking gpu: no EGL display here"), std::string::npos) << md;
  EXPECT_NE(md.find("breaking FCL: vproxq-bench-fcl failed (exit status 3): test"),
            std::string::npos) << md;
  // Exact tests are the means of the inputs.
  for (const auto& [name, sample] : scenes)
    for (const char* mode : {"off", "cpu"}) {
      const std::string mean = mean_exact_tests(runs / name / mode / "results.json");
      EXPECT_NE(md.find(std::string("| ") + name + " | " + mode + " | "), std::string::npos);
      const auto row = md.find(std::string("| ") + name + " | " + mode + " | ");
      const std::string line = md.substr(row, md.find('\n', row) - row);
      EXPECT_NE(line.find("| " + mean + " |"), std::string::npos) << line << " vs " << mean;
    }

  // results.csv: a header and one row per frame of each run (4 frames per tiny scene, 2
  // vproxq runs each, plus 2 FCL frames).
  const std::string csv = slurp(dir / "report" / "results.csv");
  EXPECT_EQ(count_lines(csv), 1u + 2 * 2 * 4 + 2);
  EXPECT_EQ(csv.rfind("scene,run,frame,", 0), 0u);
  EXPECT_NE(slurp(dir / "report" / "summary.csv").find("breaking,gpu,no EGL display here"),
            std::string::npos);
  // Gnuplot inputs: fig13 has a row per scene; fig14 says no sweep ran.
  const std::string fig13 = slurp(dir / "report" / "fig13.dat");
  EXPECT_NE(fig13.find("bowl "), std::string::npos);
  EXPECT_NE(fig13.find("breaking "), std::string::npos);
  EXPECT_NE(slurp(dir / "report" / "fig13.gp").find("set output 'fig13.png'"), std::string::npos);
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
