// Every query file of tests/data/ccd-queries (Wang et al. 2021 sample queries, exact rational
// ground truth) through the elementary CCD tests: no false negatives allowed; false positives
// are counted and printed. Also the reader's error messages.
#include <gtest/gtest.h>

#include "core/errors.hpp"
#include "core/geometry/ccd.hpp"
#include "io/ccd_queries.hpp"
#include "io_test_util.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

namespace vproxq {
namespace {

namespace fs = std::filesystem;

const fs::path kQueryDir = fs::path(VPROXQ_TEST_DATA_DIR) / "ccd-queries";

std::vector<fs::path> query_files() {
  std::vector<fs::path> files;
  for (const auto& e : fs::recursive_directory_iterator(kQueryDir))
    if (e.is_regular_file() && e.path().extension() == ".csv") files.push_back(e.path());
  std::sort(files.begin(), files.end());
  return files;
}

TEST(CcdGroundTruth, EveryQueryFileHasNoFalseNegatives) {
  const std::vector<fs::path> files = query_files();
  ASSERT_EQ(files.size(), 32u) << "expected the 8 data sets x {vertex-face, edge-edge} x 2 files";
  long total_q = 0, total_fp = 0;
  for (const fs::path& file : files) {
    const bool vf = file.parent_path().filename() == "vertex-face";
    ASSERT_TRUE(vf || file.parent_path().filename() == "edge-edge") << file;
    const std::vector<CcdQuery> queries = read_ccd_queries(file);
    ASSERT_FALSE(queries.empty()) << file;
    long collisions = 0, fp = 0, fn = 0, limit = 0;
    for (const CcdQuery& q : queries) {
      const CcdResult r = vf ? vertex_face_ccd(q.start, q.end) : edge_edge_ccd(q.start, q.end);
      collisions += q.truth;
      fp += r.collides && !q.truth;
      limit += r.hit_limit;
      if (q.truth && !r.collides) {
        ++fn;
        ADD_FAILURE() << "false negative: " << file.string() << " line " << q.line;
      }
      if (r.collides) {
        EXPECT_GE(r.toi, 0.0);
        EXPECT_LE(r.toi, 1.0);
      }
    }
    std::printf("[          ] %s/%s: queries %zu, collisions %ld, false_positives %ld, "
                "false_negatives %ld, box-limit hits %ld\n",
                file.parent_path().parent_path().filename().c_str(), (vf ? "vf" : "ee"),
                queries.size(), collisions, fp, fn, limit);
    total_q += static_cast<long>(queries.size());
    total_fp += fp;
    EXPECT_EQ(fn, 0) << file;
  }
  std::printf("[          ] all files: queries %ld, false_positives %ld\n", total_q, total_fp);
}

TEST(CcdQueryReader, ReadsRationalsExactly) {
  test::TempDir dir;
  std::string rows;
  for (int i = 0; i < 8; ++i) rows += "3,4,-1,8,12345678901234567890,1,1\n";
  const fs::path f = dir.write("q.csv", rows);
  const std::vector<CcdQuery> qs = read_ccd_queries(f);
  ASSERT_EQ(qs.size(), 1u);
  EXPECT_TRUE(qs[0].truth);
  EXPECT_EQ(qs[0].start[0].x(), 0.75);
  EXPECT_EQ(qs[0].end[3].y(), -0.125);
  EXPECT_EQ(qs[0].start[2].z(), 12345678901234567890.0);
  EXPECT_EQ(qs[0].line, 1);
}

TEST(CcdQueryReader, NumeratorsAndDenominatorsOfAnyLength) {
  // Quotients are formed before rounding to double: 10^400 / 10^400 is 1 (not inf / inf), and
  // 10^300 / 10^350 is 1e-50 (not 0).
  const std::string e400 = "1" + std::string(400, '0'), e350 = "1" + std::string(350, '0'),
                    e300 = "1" + std::string(300, '0');
  test::TempDir dir;
  std::string rows;
  for (int i = 0; i < 8; ++i) rows += e400 + "," + e400 + "," + e300 + "," + e350 + ",-" + e300 + ",1" + std::string(250, '0') + ",0\n";
  const std::vector<CcdQuery> qs = read_ccd_queries(dir.write("q.csv", rows));
  ASSERT_EQ(qs.size(), 1u);
  EXPECT_EQ(qs[0].start[0].x(), 1.0);
  EXPECT_NEAR(qs[0].start[0].y(), 1e-50, 1e-64);
  EXPECT_NEAR(qs[0].end[3].z(), -1e50, 1e36);
}

void expect_input_error(const std::string& text, const std::string& needle) {
  test::TempDir dir;
  const fs::path f = dir.write("bad.csv", text);
  EXPECT_INPUT_ERROR(read_ccd_queries(f), f.string(), needle);
}

TEST(CcdQueryReader, RejectsMalformedFiles) {
  std::string ok_row = "0,1,0,1,0,1,0\n";
  std::string seven;
  for (int i = 0; i < 7; ++i) seven += ok_row;
  expect_input_error(seven, "ends inside a query");
  expect_input_error("0,1,0,1,0,1\n", "line 1: expected 7");
  expect_input_error(ok_row + "0,1,x,1,0,1,0\n", "line 2: field 3");
  expect_input_error(ok_row + ok_row + "0,0,0,1,0,1,0\n", "line 3: zero denominator");
  // Below 2^-200 (1e-400, which a double would round to 0) and at or above 2^200.
  expect_input_error(ok_row + "0,1,1,1" + std::string(400, '0') + ",0,1,0\n", "line 2: coordinate y = 1/1000");
  expect_input_error(ok_row + "0,1,1," + std::string("1") + std::string(100, '0') + ",0,1,0\n", "too close to 0");
  expect_input_error(ok_row + "1" + std::string(61, '0') + ",1,0,1,0,1,0\n", "line 2: coordinate x = 1000");
  expect_input_error(ok_row + "1" + std::string(5000, '0') + ",1,0,1,0,1,0\n", "line 2: field 1");
  expect_input_error("0,1,0,1,0,1,2\n", "line 1: truth");
  expect_input_error(ok_row + "0,1,0,1,0,1,1\n", "line 2: truth differs");
  EXPECT_THROW(read_ccd_queries(kQueryDir / "no-such-file.csv"), InputError);
}

}  // namespace
}  // namespace vproxq
