// diff_result_files: what is compared, what is ignored, tolerances and messages.
#include "core/errors.hpp"
#include "io/output.hpp"
#include "io/result_diff.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <fstream>
#include <string>
#include <thread>
#include <utility>

#include <sys/stat.h>

#include <unistd.h>

namespace vproxq {
namespace {

namespace fs = std::filesystem;
using Json = nlohmann::ordered_json;

// A small results document in the results.json shape: three frames, the middle one without
// "distance", the last one with a lone object.
Json base_document() {
  return Json::parse(R"({
    "tool": "vproxq", "version": "0.1.0", "format_version": 1, "scene": "bowl",
    "queries": ["distance"],
    "settings": {"voronoi": "cpu", "grid": 64, "device": null, "threads": 4},
    "frames": [
      {"frame": 0,
       "objects": [{"id": 0, "name": "a", "vertices": 3, "triangles": 1},
                   {"id": 1, "name": "b", "vertices": 3, "triangles": 1, "static": true}],
       "distance": {"inter": [
         {"object": 0, "nearest_object": 1, "distance": 0.5, "triangles": [0, 0],
          "points": [[0, 0, 0], [0, 0, 0.5]]},
         {"object": 1, "nearest_object": 0, "distance": 0.5, "triangles": [0, 0],
          "points": [[0, 0, 0.5], [0, 0, 0]]}]},
       "stats": {"time_ms": {"load": 1, "aabb": 2, "voronoi": 3, "exact": 4, "write": 5,
                             "total": 15}, "exact_tests": 1, "pns_pairs": 2,
                 "feature_pns": 1}},
      {"frame": 1,
       "objects": [{"id": 0, "name": "a", "vertices": 3, "triangles": 1}],
       "stats": {"time_ms": {"load": 1, "aabb": 0, "voronoi": 0, "exact": 0, "write": 1,
                             "total": 2}, "exact_tests": 0, "pns_pairs": 0,
                 "feature_pns": 0}},
      {"frame": 3,
       "objects": [{"id": 0, "name": "a", "vertices": 3, "triangles": 1}],
       "distance": {"inter": [
         {"object": 0, "nearest_object": null, "distance": null, "triangles": null,
          "points": null}]},
       "stats": {"time_ms": {"load": 1, "aabb": 0, "voronoi": 0, "exact": 0, "write": 1,
                             "total": 2}, "exact_tests": 0, "pns_pairs": 0,
                 "feature_pns": 0}}
    ]})");
}

class DiffTest : public ::testing::Test {
 protected:
  void SetUp() override {
    const auto* info = ::testing::UnitTest::GetInstance()->current_test_info();
    dir_ = fs::temp_directory_path() /
           ("vproxq_diff_" + std::string(info->name()) + "_" + std::to_string(::getpid()));
    fs::remove_all(dir_);
    fs::create_directories(dir_);
  }
  void TearDown() override {
    std::error_code ignored;
    fs::remove_all(dir_, ignored);
  }

  fs::path save(const std::string& name, const Json& doc) const {
    const fs::path file = dir_ / name;
    std::ofstream(file) << doc.dump(1);
    return file;
  }
  fs::path save_text(const std::string& name, const std::string& text) const {
    const fs::path file = dir_ / name;
    std::ofstream(file) << text;
    return file;
  }

  DiffOutcome diff(const Json& a, const Json& b, DiffOptions opts = {}) const {
    return diff_result_files(save("a.json", a), save("b.json", b), opts);
  }

  fs::path dir_;
};

TEST_F(DiffTest, IdenticalFilesAreEqual) {
  const DiffOutcome d = diff(base_document(), base_document());
  EXPECT_TRUE(d.equal);
  EXPECT_EQ(d.first_difference, "");
}

TEST_F(DiffTest, FilesWrittenByResultWriterAreEqualToThemselves) {
  RunInfo info;
  info.scene_name = "s";
  info.queries = {"distance"};
  FrameResult f;
  f.objects = {{0, "a", 3, 1, false}};
  f.inter = std::vector<InterObjectDistance>(1);
  (*f.inter)[0].object = 0;
  for (const char* out : {"run1", "run2"}) {
    ResultWriter w(dir_ / out, info);
    w.write_frame(f);
    w.commit();
  }
  // The two runs differ at least in stats.time_ms.write, which is ignored.
  EXPECT_TRUE(diff_result_files(dir_ / "run1" / "results.json", dir_ / "run2" / "results.json",
                                {})
                  .equal);
}

TEST_F(DiffTest, StatsVersionAndSettingsAreIgnored) {
  Json b = base_document();
  b["version"] = "9.9.9";
  b["settings"] = {{"voronoi", "gpu"}, {"grid", nullptr}, {"device", "llvmpipe"}};
  b["frames"][0]["stats"]["exact_tests"] = 12345;
  b["frames"][1]["stats"]["time_ms"]["total"] = 99.5;
  b["frames"][2].erase("stats");
  EXPECT_TRUE(diff(base_document(), b).equal);
}

TEST_F(DiffTest, IgnoredMembersAreLeftOutAtEveryDepth) {
  // A key that one file has and the other lacks (a key added in a later version), deep inside
  // a frame: a difference, unless ignored.
  Json b = base_document();
  b["frames"][0]["distance"]["inter"][0]["reason"] = "added";
  DiffOutcome d = diff(base_document(), b);
  EXPECT_FALSE(d.equal);
  EXPECT_EQ(d.first_difference, "frame 0 (frames[0]), distance.inter[0].reason: (missing) vs \"added\"");
  DiffOptions opts;
  opts.ignore = {"reason"};
  EXPECT_TRUE(diff(base_document(), b, opts).equal);
  EXPECT_TRUE(diff(b, base_document(), opts).equal);
  // A name is left out at every depth where it occurs: "distance" is a frame's member and an
  // inter entry's; a change elsewhere still shows.
  Json c = base_document();
  c["frames"][0]["distance"]["inter"][1]["distance"] = 0.25;
  c["frames"][2].erase("distance");
  opts.ignore = {"distance"};
  EXPECT_TRUE(diff(base_document(), c, opts).equal);
  c["frames"][1]["objects"][0]["triangles"] = 2;
  d = diff(base_document(), c, opts);
  EXPECT_FALSE(d.equal);
  EXPECT_EQ(d.first_difference, "frame 1 (frames[1]), objects[0].triangles: 1 vs 2");
  // Top-level members too.
  Json e = base_document();
  e["scene"] = "skirt";
  opts.ignore = {"reason", "scene"};
  EXPECT_TRUE(diff(base_document(), e, opts).equal);
}

TEST_F(DiffTest, DistanceBeyondToleranceDiffersWithReadablePath) {
  Json b = base_document();
  b["frames"][0]["distance"]["inter"][1]["distance"] = 0.25;
  const DiffOutcome d = diff(base_document(), b);
  EXPECT_FALSE(d.equal);
  EXPECT_EQ(d.first_difference, "frame 0 (frames[0]), distance.inter[1].distance: 0.5 vs 0.25");
}

TEST_F(DiffTest, RelativeToleranceAcceptsSmallDifferences) {
  Json b = base_document();
  b["frames"][0]["distance"]["inter"][0]["distance"] = 0.5 * (1 + 1e-9);
  EXPECT_FALSE(diff(base_document(), b).equal);
  DiffOptions loose;
  loose.rtol = 1e-8;
  EXPECT_TRUE(diff(base_document(), b, loose).equal);
  DiffOptions tight;
  tight.rtol = 1e-10;
  EXPECT_FALSE(diff(base_document(), b, tight).equal);
}

TEST_F(DiffTest, AbsoluteToleranceAcceptsSmallDifferences) {
  Json b = base_document();
  b["frames"][0]["distance"]["inter"][0]["points"][0][2] = 1e-12;  // was 0: rtol cannot help
  DiffOptions rtol_only;
  rtol_only.rtol = 1e-3;
  const DiffOutcome d = diff(base_document(), b, rtol_only);
  EXPECT_FALSE(d.equal);
  EXPECT_EQ(d.first_difference,
            "frame 0 (frames[0]), distance.inter[0].points[0][2]: 0 vs 1e-12");
  DiffOptions abs;
  abs.atol = 1e-11;
  EXPECT_TRUE(diff(base_document(), b, abs).equal);
  abs.atol = 1e-13;
  EXPECT_FALSE(diff(base_document(), b, abs).equal);
}

TEST_F(DiffTest, IntegersAndFloatsCompareAsNumbers) {
  Json b = base_document();
  b["frames"][0]["distance"]["inter"][0]["points"][0][0] = 0.0;  // 0 in a
  b["frames"][0]["objects"][0]["vertices"] = 3.0;
  EXPECT_TRUE(diff(base_document(), b).equal);
}

TEST_F(DiffTest, IntegersAreComparedExactlyWhateverTheTolerance) {
  // Ids, counts and frame numbers are answers: a tolerance meant for distances must not let
  // triangle 1000001 pass for 1000000, and integers beyond 2^53 must not merge in a double.
  DiffOptions loose;
  loose.rtol = 1e-3;
  loose.atol = 1;
  Json b = base_document();
  b["frames"][0]["distance"]["inter"][0]["triangles"][0] =
      b["frames"][0]["distance"]["inter"][0]["triangles"][0].get<std::int64_t>() + 1;
  const DiffOutcome d = diff(base_document(), b, loose);
  EXPECT_FALSE(d.equal);
  EXPECT_NE(d.first_difference.find("triangles[0]"), std::string::npos) << d.first_difference;
  Json big_a = base_document(), big_b = base_document();
  big_a["frames"][0]["objects"][0]["vertices"] = std::uint64_t{1} << 53;
  big_b["frames"][0]["objects"][0]["vertices"] = (std::uint64_t{1} << 53) + 1;
  EXPECT_FALSE(diff(big_a, big_b).equal);
  // Doubles within the tolerance still pass.
  Json c = base_document();
  c["frames"][0]["distance"]["inter"][0]["distance"] =
      c["frames"][0]["distance"]["inter"][0]["distance"].get<double>() + 0.5;
  EXPECT_TRUE(diff(base_document(), c, loose).equal);
}

TEST_F(DiffTest, NullVersusNumberDiffers) {
  Json b = base_document();
  b["frames"][2]["distance"]["inter"][0]["distance"] = 1.5;
  const DiffOutcome d = diff(base_document(), b, {1e9, 1e9, {}});
  EXPECT_FALSE(d.equal);
  EXPECT_EQ(d.first_difference, "frame 3 (frames[2]), distance.inter[0].distance: null vs 1.5");
}

TEST_F(DiffTest, MissingKeyDiffers) {
  Json b = base_document();
  b["frames"][0]["objects"][1].erase("static");
  DiffOutcome d = diff(base_document(), b);
  EXPECT_FALSE(d.equal);
  EXPECT_EQ(d.first_difference, "frame 0 (frames[0]), objects[1].static: true vs (missing)");

  // ... in either file.
  d = diff(b, base_document());
  EXPECT_FALSE(d.equal);
  EXPECT_EQ(d.first_difference, "frame 0 (frames[0]), objects[1].static: (missing) vs true");

  // A whole query missing from one frame.
  Json c = base_document();
  c["frames"][1]["distance"] = {{"inter", Json::array()}};
  d = diff(base_document(), c);
  EXPECT_FALSE(d.equal);
  EXPECT_EQ(d.first_difference, "frame 1 (frames[1]), distance: (missing) vs {\"inter\":[]}");
}

TEST_F(DiffTest, DifferentFrameCountDiffers) {
  Json b = base_document();
  b["frames"].erase(2);
  const DiffOutcome d = diff(base_document(), b);
  EXPECT_FALSE(d.equal);
  EXPECT_EQ(d.first_difference, "frames: 3 vs 2 entries");
}

TEST_F(DiffTest, ArrayLengthAndStringAndBoolDifferences) {
  Json b = base_document();
  b["frames"][0]["distance"]["inter"].erase(1);
  EXPECT_EQ(diff(base_document(), b).first_difference,
            "frame 0 (frames[0]), distance.inter: 2 vs 1 entries");

  Json c = base_document();
  c["frames"][1]["objects"][0]["name"] = "A";
  EXPECT_EQ(diff(base_document(), c).first_difference,
            "frame 1 (frames[1]), objects[0].name: \"a\" vs \"A\"");

  Json e = base_document();
  e["frames"][0]["objects"][1]["static"] = false;
  EXPECT_EQ(diff(base_document(), e).first_difference,
            "frame 0 (frames[0]), objects[1].static: true vs false");

  Json s = base_document();
  s["scene"] = "other";
  EXPECT_EQ(diff(base_document(), s).first_difference, "scene: \"bowl\" vs \"other\"");
}

TEST_F(DiffTest, FirstDifferenceIsReportedInFileOrder) {
  Json b = base_document();
  b["frames"][2]["objects"][0]["triangles"] = 2;
  b["frames"][0]["distance"]["inter"][0]["triangles"][1] = 7;
  b["frames"][0]["objects"][0]["triangles"] = 9;
  EXPECT_EQ(diff(base_document(), b).first_difference,
            "frame 0 (frames[0]), objects[0].triangles: 1 vs 9");
}

TEST_F(DiffTest, MalformedFileThrowsInputErrorNamingIt) {
  const fs::path good = save("good.json", base_document());
  const fs::path bad = save_text("bad.json", "{\"frames\": [ {\"frame\": 0, ");
  try {
    diff_result_files(good, bad, {});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(bad.string()), std::string::npos) << e.what();
  }
  EXPECT_THROW(diff_result_files(bad, good, {}), InputError);
  const fs::path not_results = save_text("array.json", "[1, 2, 3]");
  EXPECT_THROW(diff_result_files(good, not_results, {}), InputError);
  // Nesting far beyond a results file's few levels is refused while parsing (comparing it
  // recursed that deep and overflowed the stack).
  const fs::path deep = save_text("deep.json", "{\"frames\": " + std::string(100000, '[') + std::string(100000, ']') + "}");
  try {
    diff_result_files(deep, deep, {});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find("nested more than"), std::string::npos) << e.what();
  }
  // A key given twice in one object (only the last value would be compared), and a number
  // beyond double's range, are malformed too.
  const fs::path twice = save_text("twice.json", R"({"frames": [{"frame": 0, "x": 1, "x": 2}]})");
  const fs::path once = save_text("once.json", R"({"frames": [{"frame": 0, "x": 2}]})");
  const fs::path huge = save_text("huge.json", R"({"frames": [{"frame": 0, "x": 1e400}]})");
  // Integers are compared exactly: one beyond 64 bits (parsed as a double) cannot be.
  const fs::path wide = save_text("wide.json", R"({"frames": [{"frame": 0, "x": -9223372036854775809}]})");
  for (const auto& [file, phrase] : {std::pair{twice, "the key \"x\" appears twice in one object"},
                                     std::pair{huge, "number overflow"},
                                     std::pair{wide, "the integer -9223372036854775809 does not fit in 64 bits"}}) {
    try {
      diff_result_files(file, once, {});
      ADD_FAILURE() << "expected InputError for " << file;
    } catch (const InputError& e) {
      EXPECT_NE(std::string(e.what()).find("malformed results file '" + file.string() + "': "), std::string::npos) << e.what();
      EXPECT_NE(std::string(e.what()).find(phrase), std::string::npos) << e.what();
    }
  }
}

// A results file can come through a pipe (`vproxq diff <(jq . a.json) b.json`): it is read once.
TEST_F(DiffTest, AResultsFileCanBeAPipe) {
  const Json doc = base_document();
  const fs::path file = save("file.json", doc);
  const fs::path fifo = dir_ / "fifo.json";
  ASSERT_EQ(::mkfifo(fifo.c_str(), 0600), 0);
  std::thread writer([&] { std::ofstream(fifo) << doc.dump(); });
  const DiffOutcome outcome = diff_result_files(fifo, file, {});
  writer.join();
  EXPECT_TRUE(outcome.equal) << outcome.first_difference;
}

TEST_F(DiffTest, MissingFileThrowsInputErrorNamingIt) {
  const fs::path good = save("good.json", base_document());
  const fs::path missing = dir_ / "missing.json";
  try {
    diff_result_files(good, missing, {});
    FAIL() << "expected InputError";
  } catch (const InputError& e) {
    EXPECT_NE(std::string(e.what()).find(missing.string()), std::string::npos) << e.what();
  }
}

}  // namespace
}  // namespace vproxq
