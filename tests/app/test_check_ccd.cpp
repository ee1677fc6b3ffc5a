// End-to-end tests of `vproxq check-ccd FILE.csv --type vf|ee`: the summary line, its counts
// against the library's kernel on the same file, and the error paths with their exit codes.
#include "core/geometry/ccd.hpp"
#include "io/ccd_queries.hpp"
#include "support/cli.hpp"

#include <gtest/gtest.h>

#include <regex>
#include <string>

namespace vproxq {
namespace {

namespace fs = std::filesystem;
using test::quote;
using test::run_command;
using test::ScratchDir;
using test::vproxq;

const fs::path kQueries = fs::path(VPROXQ_TEST_DATA_DIR) / "ccd-queries";


std::string last_line(const std::string& out) {
  std::string s = out;
  while (!s.empty() && s.back() == '\n') s.pop_back();
  const auto nl = s.rfind('\n');
  return nl == std::string::npos ? s : s.substr(nl + 1);
}

void expect_summary_matches_kernel(const fs::path& file, bool vf) {
  const auto r = vproxq("check-ccd " + quote(file) + (vf ? " --type vf" : " --type ee"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  long n = 0, c = 0, fp = 0, fn = 0;
  for (const CcdQuery& q : read_ccd_queries(file)) {
    const CcdResult k = vf ? vertex_face_ccd(q.start, q.end) : edge_edge_ccd(q.start, q.end);
    ++n;
    c += k.collides;
    fp += k.collides && !q.truth;
    fn += !k.collides && q.truth;
  }
  EXPECT_EQ(last_line(r.output), "queries: " + std::to_string(n) + ", collisions: " +
                                     std::to_string(c) + ", false_positives: " +
                                     std::to_string(fp) + ", false_negatives: " + std::to_string(fn));
  EXPECT_TRUE(std::regex_match(last_line(r.output),
                               std::regex("queries: [0-9]+, collisions: [0-9]+, "
                                          "false_positives: [0-9]+, false_negatives: 0")))
      << r.output;
}

TEST(CheckCcdCli, SummaryLineOnGroundTruth) {
  expect_summary_matches_kernel(kQueries / "unit-tests/vertex-face/data_0_0.csv", true);
  expect_summary_matches_kernel(kQueries / "erleben-spikes/edge-edge/data_0_0.csv", false);
}

std::string rows(const std::string& row, int n) {
  std::string s;
  for (int i = 0; i < n; ++i) s += row;
  return s;
}

TEST(CheckCcdCli, FalseNegativeIsReported) {
  ScratchDir dir;
  // A vertex far above a triangle that stays put, labelled as colliding: the kernel must say
  // no, so the file's label is a false negative of the kernel by the file's own truth.
  const std::string text = "0,1,0,1,10,1,1\n0,1,0,1,0,1,1\n1,1,0,1,0,1,1\n0,1,1,1,0,1,1\n"
                           "0,1,0,1,11,1,1\n0,1,0,1,0,1,1\n1,1,0,1,0,1,1\n0,1,1,1,0,1,1\n";
  const auto f = dir.write("fn.csv", text);
  const auto r = vproxq("check-ccd " + quote(f) + " --type vf");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_EQ(last_line(r.output), "queries: 1, collisions: 0, false_positives: 0, false_negatives: 1");
  EXPECT_NE(r.output.find("fn.csv:1"), std::string::npos) << r.output;
}

TEST(CheckCcdCli, InputErrors) {
  ScratchDir dir;
  auto r = vproxq("check-ccd " + quote(dir / "missing.csv") + " --type vf");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("missing.csv"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("queries:"), std::string::npos) << r.output;

  const auto bad = dir.write("bad.csv", rows("0,1,0,1,0,1,0\n", 3) + "0,1,zz,1,0,1,0\n" +
                                            rows("0,1,0,1,0,1,0\n", 4));
  r = vproxq("check-ccd " + quote(bad) + " --type ee");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("bad.csv: line 4"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("queries:"), std::string::npos) << r.output;

  // A coordinate outside the range the readers accept (here 1 / 10^70 < 2^-200): the
  // kernel's guarantees do not cover it, so it is an input error, not a reported miss.
  const std::string tiny = "1," + std::string("1") + std::string(70, '0') + ",0,1,0,1,1\n";
  const auto small = dir.write("small.csv", rows("0,1,0,1,0,1,1\n", 2) + tiny + rows("0,1,0,1,0,1,1\n", 5));
  r = vproxq("check-ccd " + quote(small) + " --type vf");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("small.csv: line 3"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("too close to 0"), std::string::npos) << r.output;

  const auto cut = dir.write("cut.csv", rows("0,1,0,1,0,1,0\n", 12));
  r = vproxq("check-ccd " + quote(cut) + " --type ee");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("ends inside a query"), std::string::npos) << r.output;
}

TEST(CheckCcdCli, UsageErrors) {
  const fs::path f = kQueries / "unit-tests/vertex-face/data_0_0.csv";
  auto r = vproxq("check-ccd " + quote(f) + " --type xy");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--type"), std::string::npos) << r.output;
  r = vproxq("check-ccd " + quote(f));
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = vproxq("check-ccd --type vf");
  EXPECT_EQ(r.exit_code, 2) << r.output;
}

}  // namespace
}  // namespace vproxq
