// End-to-end tests of the CLI: bad input gets its message and exit code; results equal brute
// force; runs are reproducible and `vproxq diff` says so.
#include "core/query/inter_distance.hpp"
#include "io/scene_source.hpp"
#include "support/cli.hpp"
#include "support/random_scene.hpp"

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include <cctype>
#include <csignal>
#include <fstream>

#include <sys/wait.h>
#include <unistd.h>

namespace vproxq {
namespace {

using test::slurp;

namespace fs = std::filesystem;
using test::quote;
using test::run_command;
using test::ScratchDir;
using test::read_json;
using test::vproxq;
using test::write_obj;

const fs::path kSamples = VPROXQ_SAMPLE_SCENES_DIR;




/// Every frame of results.json equals the brute force on the frames the scene loads.
void expect_results_equal_brute_force(const fs::path& scene_path, const fs::path& results) {
  const SceneSource scene = SceneSource::open(scene_path);
  const nlohmann::json j = read_json(results);
  ASSERT_EQ(j.at("frames").size(), scene.frame_count());
  for (size_t k = 0; k < scene.frame_count(); ++k) {
    const Frame frame = scene.load_frame(k);
    const auto ref = inter_object_distance_brute_force(frame);
    const auto& inter = j["frames"][k]["distance"]["inter"];
    ASSERT_EQ(inter.size(), ref.per_object.size());
    for (size_t i = 0; i < ref.per_object.size(); ++i) {
      const auto& r = ref.per_object[i];
      SCOPED_TRACE("frame " + std::to_string(k) + " object " + std::to_string(i));
      EXPECT_EQ(inter[i]["object"].get<int>(), static_cast<int>(i));
      if (!r.has_nearest()) {
        EXPECT_TRUE(inter[i]["nearest_object"].is_null());
        continue;
      }
      EXPECT_EQ(inter[i]["nearest_object"].get<int>(), r.nearest_object);
      EXPECT_EQ(inter[i]["distance"].get<double>(), r.distance);  // JSON round-trips doubles
      EXPECT_EQ(inter[i]["triangles"][0].get<int>(), r.triangles[0]);
      EXPECT_EQ(inter[i]["triangles"][1].get<int>(), r.triangles[1]);
      for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(inter[i]["points"][0][c].get<double>(), r.points[0][c]);
        EXPECT_EQ(inter[i]["points"][1][c].get<double>(), r.points[1][c]);
      }
    }
  }
}

TEST(Cli, HelpAndVersion) {
  auto r = vproxq("--help");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // A list option reads as one comma-separated value (CLI11's own label was "TEXT ...", which
  // reads as several space-separated ones, and those are not taken).
  EXPECT_NE(r.output.find("--queries Q[,Q...]"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Valid: distance, ccd, pd"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("Exit codes"), std::string::npos);
  // What each query answers, one entry per query.
  for (const char* entry : {"\n  distance  each object's", "\n  ccd       every vertex-face", "\n  pd        the local"})
    EXPECT_NE(r.output.find(entry), std::string::npos) << entry << "\n" << r.output;
  r = vproxq("--version");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find(VPROXQ_VERSION), std::string::npos);
  r = vproxq("diff --help");
  EXPECT_EQ(r.exit_code, 0);
  EXPECT_NE(r.output.find("--ignore KEY[,KEY...]"), std::string::npos) << r.output;
  // The subcommands answer --version too (it was "A is required").
  for (const char* sub : {"diff", "check-ccd"}) {
    r = vproxq(std::string(sub) + " --version");
    EXPECT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(r.output, std::string("vproxq ") + VPROXQ_VERSION + "\n");
  }
}

TEST(Cli, OptionsTheBackendDoesNotUseAreNoted) {
  const std::string scene = quote(kSamples / "two-cubes" / "scene.json");
  auto r = vproxq(scene + " --grid 64 --device 0");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("note: --grid has no effect with --voronoi=off"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("note: --device has no effect with --voronoi=off"), std::string::npos) << r.output;
  r = vproxq(scene + " --grid 64 --voronoi=cpu");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("note:"), std::string::npos) << r.output;
  r = vproxq(scene + " --grid 64 --quiet");
  EXPECT_EQ(r.output.find("note:"), std::string::npos) << r.output;
  // With a backend, options that no query of the run reads are noted too.
  r = vproxq(scene + " --grid 64 --voronoi=cpu --queries=pd");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("note: --grid has no effect without the distance query"), std::string::npos) << r.output;
  r = vproxq(scene + " --ccd-grid 8 --voronoi=cpu --queries=distance");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("note: --ccd-grid has no effect without the ccd query"), std::string::npos) << r.output;
  r = vproxq(scene + " --grid 64 --ccd-grid 8 --voronoi=cpu --queries=distance,ccd");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("note:"), std::string::npos) << r.output;
}

// Error messages quote bytes of the input as valid UTF-8: a Latin-1 byte of a mesh file shows as
// U+FFFD, never raw.
TEST(Cli, ErrorMessagesShowInputBytesAsValidUtf8) {
  ScratchDir dir;
  const auto mesh = dir.write("latin1.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\ncaf\xe9 1 2 3\nf 1 2 3\n");
  const auto r = vproxq(quote(mesh));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("latin1.obj"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("caf\xef\xbf\xbd"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find('\xe9'), std::string::npos) << r.output;
}

TEST(Cli, UsageErrors) {
  const std::string scene = quote(kSamples / "two-cubes" / "scene.json");
  auto r = vproxq(scene + " --queries=distance,bogus");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("unknown query 'bogus'"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("valid queries: distance, ccd, pd"), std::string::npos) << r.output;
  r = vproxq(scene + " --queries=,");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  // Empty items and repeats are errors (as in scene.json), and a value with no item does not
  // take the next argument as its own: the message is about --queries.
  for (const auto& [args, says] : std::vector<std::pair<std::string, std::string>>{
           {scene + " --queries=distance,distance", "'distance' is given twice"},
           {scene + " --queries distance --queries pd,distance", "'distance' is given twice"},
           {scene + " --queries=,distance", "an empty item"},
           {scene + " --queries=distance,,pd", "an empty item"},
           {scene + " --queries=, -q", "--queries ',': an empty item"},
           {"--queries=, " + scene, "--queries ',': an empty item"},
           {scene + " --queries= -q", "--queries has no value"},
           {scene + " --frames= -q", "--frames has no value"},
           // -o=OUT would write into a directory named "=OUT".
           {scene + " -o=out -q", "-o=out: write -o out or --output=out"},
           {scene + " -o= -q", "-o= has no value: write -o OUT, -oOUT or --output=OUT"},
           // An option of one value given more than once (CLI11: "At Most 1 required").
           {scene + " --grid 8 --grid 9 -q", "--grid is given 2 times; it takes one value"},
           {scene + " --threads 1 --threads 2 --threads 1 -q", "--threads is given 3 times; it takes one value"},
           {"diff a.json b.json --rtol 1 --rtol 2", "--rtol is given 2 times; it takes one value"}}) {
    SCOPED_TRACE(args);
    r = vproxq(args);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(says), std::string::npos) << r.output;
  }
  // The option may be repeated: its lists are joined.
  {
    ScratchDir dir;
    r = vproxq(scene + " --queries distance --queries pd --quiet -o " + quote(dir / "out"));
    EXPECT_EQ(r.exit_code, 0) << r.output;
    const auto frame = read_json(dir / "out" / "results.json")["frames"][0];
    EXPECT_TRUE(frame.contains("distance") && frame.contains("pd")) << frame.dump().substr(0, 300);
  }
  r = vproxq(scene + " --voronoi=sometimes");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  // Numeric options name their range and the value given.
  for (const std::string bad : {"--threads=-3", "--threads=abc", "--threads=100000", "--threads=1.5",
                                "--device=-1", "--device=x", "--grid=-2", "--grid=99999999999999999999"}) {
    SCOPED_TRACE(bad);
    r = vproxq(scene + " " + bad + " --quiet");
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find(bad.substr(0, bad.find('='))), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("got '" + bad.substr(bad.find('=') + 1) + "'"), std::string::npos) << r.output;
  }
  r = vproxq(scene + " --grid=0");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = vproxq(scene + " -o ''");  // not "no output": a usage error
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--output"), std::string::npos) << r.output;
  r = vproxq(scene + " --grid=4097");  // past kMaxGridResolution
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("--grid"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("4096"), std::string::npos) << r.output;
  r = vproxq(scene + " --frames=7:9");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("has 3 frames"), std::string::npos) << r.output;
  r = vproxq(scene + " --frames=2:1");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = vproxq(scene + " --frames=:0");  // the same empty range as 0:0, not a run of 0 frames
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("empty"), std::string::npos) << r.output;
  // --queries takes one comma-separated value: before SCENE it leaves SCENE alone, and a
  // space-separated list is not silently taken.
  r = vproxq("--queries=distance,ccd " + scene + " --quiet");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = vproxq(scene + " --queries distance ccd --quiet");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("ccd"), std::string::npos) << r.output;
  r = vproxq(scene + " --frames=x");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = vproxq(scene + " --frames=99999999999999999999:");  // past long: a usage error, not a crash
  EXPECT_EQ(r.exit_code, 2) << r.output;
  EXPECT_NE(r.output.find("too large"), std::string::npos) << r.output;
  r = vproxq(scene + " --frames=0001:2 --quiet");  // leading zeros are fine
  EXPECT_EQ(r.exit_code, 0) << r.output;
  r = vproxq("");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = vproxq(scene + " --no-such-option");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  r = vproxq("diff onlyone.json");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  for (const std::string bad : {"--rtol=-1", "--rtol=nan", "--atol=inf", "--atol=1e-3x"}) {
    SCOPED_TRACE(bad);
    r = vproxq("diff a.json b.json " + bad);
    EXPECT_EQ(r.exit_code, 2) << r.output;
    EXPECT_NE(r.output.find("expected a finite number >= 0"), std::string::npos) << r.output;
  }
}

/// A scene directory with frames written from random blobs, for the input-error cases.
struct BadInputCase {
  std::string name;
  std::string frame0, frame1;  // OBJ texts
  std::string expect;          // substring of the message
};

TEST(Cli, InputErrorsNameTheFileAndLeaveNoOutput) {
  const std::string good = "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n";
  const std::vector<BadInputCase> cases = {
      {"malformed", good, "o a\nv 0 0 zero\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "frame_1.obj"},
      {"index_out_of_range", good, "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 9\n", "out of range"},
      {"nan", good, "o a\nv 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "frame_1.obj"},
      {"inf", good, "o a\nv 0 0 inf\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "frame_1.obj"},
      {"out_of_range", good, "o a\nv 0 0 1e61\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "frame_1.obj: line 2: vertex 1 has a coordinate out of range"},
      {"empty_frame", good, "# nothing here\n", "frame_1.obj"},
      {"object_count", good, "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n", "frame_1.obj"},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    ScratchDir dir;
    dir.write("frame_0.obj", c.frame0);
    dir.write("frame_1.obj", c.frame1);
    const auto scene = dir.write(
        "scene.json", R"({"frames": {"pattern": "frame_%d.obj", "first": 0, "count": 2}})");
    const auto out = dir / "out";
    const auto r = vproxq(quote(scene) + " -o " + quote(out) + " --quiet");
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_NE(r.output.find(c.expect), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out)) << "the output directory the run created is left behind";
  }
}

// Frames are read one ahead on a background thread (with --threads below the core count, for
// frames that take over 1 ms to read: the frames here hold two sheets of 12,800 triangles): a
// bad frame still fails the run only when the run needs it (frame 2 below: not for
// --frames 0:2, but for CCD's step 1 -> 2), with the same message and exit code and no output,
// whichever frames were computed before; in line (all threads) alike.
TEST(Cli, ABadFrameFailsOnlyARunThatNeedsIt) {
  constexpr int kSide = 81;  // vertices per side of each sheet
  std::string good;
  for (int sheet = 0; sheet < 2; ++sheet) {
    good += "o sheet" + std::to_string(sheet) + "\n";
    for (int y = 0; y < kSide; ++y)
      for (int x = 0; x < kSide; ++x)
        good += "v " + std::to_string(x * 0.01) + " " + std::to_string(y * 0.01) + " " + std::to_string(sheet * 0.5) + "\n";
    const int base = sheet * kSide * kSide + 1;
    for (int y = 0; y + 1 < kSide; ++y)
      for (int x = 0; x + 1 < kSide; ++x) {
        const int v = base + y * kSide + x;
        good += "f " + std::to_string(v) + " " + std::to_string(v + 1) + " " + std::to_string(v + kSide) + "\n";
        good += "f " + std::to_string(v + 1) + " " + std::to_string(v + kSide + 1) + " " + std::to_string(v + kSide) + "\n";
      }
  }
  ScratchDir dir;
  for (int k = 0; k < 4; ++k)
    dir.write("frame_" + std::to_string(k) + ".obj", k == 2 ? good + "v 0 0 zero\n" : good);
  const auto scene = dir.write("scene.json", R"({"frames": {"pattern": "frame_%d.obj", "first": 0, "count": 4}})");
  const auto out = dir / "out";
  for (const std::string threads : {" --threads 1", ""}) {
    SCOPED_TRACE(threads);
    auto r = vproxq(quote(scene) + threads + " --frames 0:2 -o " + quote(out) + " --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(read_json(out / "results.json")["frames"].size(), 2u);
    fs::remove_all(out);
    for (const std::string& args : {std::string(" --frames 0:2 --queries distance,ccd"), std::string(""),
                                    std::string(" --frames 1: --voronoi=cpu --queries distance,ccd,pd")}) {
      SCOPED_TRACE(args);
      r = vproxq(quote(scene) + threads + args + " -o " + quote(out) + " --quiet");
      EXPECT_EQ(r.exit_code, 3) << r.output;
      EXPECT_NE(r.output.find("frame_2.obj"), std::string::npos) << r.output;
      EXPECT_FALSE(fs::exists(out)) << r.output;
    }
  }
}

// A frame file that does not exist (yet: a simulation still writing its frames) fails only a run
// that reads it, as a bad one does: --frames 0:2 needs frames 0 and 1, and with CCD frame 2 too.
// The message names scene.json, the key, the frame and the file; nothing is written.
TEST(Cli, AMissingFrameFileFailsOnlyARunThatReadsIt) {
  ScratchDir dir;
  const std::string mesh = "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n";
  dir.write("f_0.obj", mesh);
  dir.write("f_1.obj", mesh);
  for (const std::string frames : {R"({"pattern": "f_%d.obj", "count": 4})", R"({"files": ["f_0.obj", "f_1.obj", "f_2.obj", "f_3.obj"]})"}) {
    SCOPED_TRACE(frames);
    const auto scene = dir.write("scene.json", R"({"frames": )" + frames + "}");
    const auto out = dir / "out";
    auto r = vproxq(quote(scene) + " --frames 0:2 -o " + quote(out) + " --quiet");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    EXPECT_EQ(read_json(out / "results.json")["frames"].size(), 2u);
    fs::remove_all(out);
    r = vproxq(quote(scene) + " --frames 1 --queries distance,ccd -o " + quote(out) + " --quiet");
    EXPECT_EQ(r.exit_code, 3) << r.output;
    const std::string key = frames.find("pattern") != std::string::npos ? "\"frames.pattern\"" : "\"frames.files[2]\"";
    EXPECT_NE(r.output.find(scene.string() + ": " + key + " frame 2: file not found: "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("f_2.obj"), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(out)) << r.output;
    // All frames (the default range), without -o: the error, and nothing on stdout.
    r = test::run_command("{ " + std::string(VPROXQ_BINARY) + " " + quote(scene) + " > " + quote(dir / "stdout.txt") + "; }");
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_NE(r.output.find("frame 2: file not found"), std::string::npos) << r.output;
    EXPECT_EQ(slurp(dir / "stdout.txt"), "");
  }
}

// A run ended by SIGTERM or SIGHUP (a timeout, a closed terminal; SIGINT is handled the same
// way, but a shell starts background jobs with it ignored) removes its temporary files and the
// directories it created, then ends by that signal. The run is a slow one (a very fine grid on
// one thread), signalled once its temporary files exist.
// A crash (SIGSEGV, SIGABRT, ...) is cleaned up the same way; those are sent here with kill. So
// are the other signals that end a process by default: a CPU-time limit (SIGXCPU), SIGALRM,
// SIGUSR1 (SIGQUIT too, but a shell starts background jobs with it ignored, as SIGINT).
TEST(Cli, ARunEndedByASignalLeavesNothingBehind) {
  for (const auto& [sig, number] : {std::pair<const char*, int>{"TERM", 15}, {"HUP", 1}, {"SEGV", 11}, {"ABRT", 6},
                                    {"XCPU", 24}, {"ALRM", 14}, {"USR1", 10}}) {
    SCOPED_TRACE(sig);
    ScratchDir dir;
    const auto out = dir / "a" / "out";
    const std::string run = std::string(VPROXQ_BINARY) + " " + quote(kSamples / "skirt-tiny" / "scene.json") +
                            " --voronoi=cpu --grid 4096 --threads 1 --quiet -o " + quote(out);
    // (ASAN_OPTIONS: in a VPROXQ_SANITIZE build, AddressSanitizer would take SIGSEGV for itself.)
    const auto r = test::run_command("ulimit -c 0; ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}handle_segv=0 " + run +
                                     " & pid=$!; for i in $(seq 600); do ls " + quote(out) +
                                     "/.results.json.tmp-* >/dev/null 2>&1 && break; sleep 0.05; done; kill -" +
                                     sig + " $pid; wait $pid; echo \"status $?\"");
    EXPECT_NE(r.output.find("status " + std::to_string(128 + number)), std::string::npos) << r.output;
    EXPECT_FALSE(fs::exists(dir / "a")) << r.output;
  }
}

// Two runs into one output directory at the same time could leave one run's results.json
// beside the other's results.h5: the second fails at once (runtime error, naming the
// directory) and leaves the first's files alone; once the first has ended, the directory can
// be used again.
TEST(Cli, ASecondRunIntoAnOutputDirectoryInUseFails) {
  ScratchDir dir;
  const auto out = dir / "a" / "out";
  const std::string first = std::string(VPROXQ_BINARY) + " " + quote(kSamples / "skirt-tiny" / "scene.json") +
                            " --voronoi=cpu --grid 4096 --threads 1 --quiet -o " + quote(out);
  const std::string second =
      std::string(VPROXQ_BINARY) + " " + quote(kSamples / "two-cubes" / "scene.json") + " --quiet -o " + quote(out);
  const auto r = test::run_command(first + " & pid=$!; for i in $(seq 600); do ls " + quote(out) +
                                   "/.results.json.tmp-* >/dev/null 2>&1 && break; sleep 0.05; done; " + second +
                                   " 2>&1; echo \"second $?\"; ls -a " + quote(out) + "; kill -TERM $pid; wait $pid; echo \"first $?\"");
  EXPECT_NE(r.output.find("second 4"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("'" + out.string() + "' is in use by another vproxq run"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find(".results.json.tmp-"), std::string::npos) << r.output;  // the first's, left alone
  EXPECT_EQ(r.output.find("results.json\n"), std::string::npos) << r.output;    // nothing committed
  EXPECT_NE(r.output.find("first 143"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "a")) << r.output;
  const auto again = vproxq(quote(kSamples / "two-cubes" / "scene.json") + " --frames 0:1 --quiet -o " + quote(out));
  EXPECT_EQ(again.exit_code, 0) << again.output;
  EXPECT_TRUE(fs::exists(out / "results.json"));
}

// A write past the file-size limit (`ulimit -f`) would end the run by SIGXFSZ, leaving its
// temporary files; it fails instead, as any failed write does: the runtime-error exit code, a
// message naming the file and the problem, and nothing left behind.
TEST(Cli, AWritePastTheFileSizeLimitIsAnErrorThatLeavesNothingBehind) {
  ScratchDir dir;
  const auto out = dir / "a" / "out";
  // 8 blocks (4 KiB with dash's 512-byte blocks, 8 KiB with bash's 1024): below the size of
  // this scene's results.h5 either way (over 30 KiB).
  const auto r = test::run_command("ulimit -c 0; ulimit -f 8; " + std::string(VPROXQ_BINARY) + " " +
                                   quote(kSamples / "skirt-tiny" / "scene.json") + " --quiet -o " + quote(out) +
                                   " 2>&1; echo \"status $?\"");
  EXPECT_NE(r.output.find("status 4"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("File too large"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find((out / ".results.").string()), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "a")) << r.output;
}

// Without -o the summary on stdout is printed whole when the run ends: a run that fails part-way
// (frame 1's object count differs from frame 0's) prints none of frame 0's, as it writes no
// files; and a summary write past the file-size limit is a runtime error (exit 4, naming
// standard output), not the end by SIGXFSZ.
TEST(Cli, TheSummaryIsPrintedWholeOrNotAtAll) {
  ScratchDir dir;
  const std::string two = "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n";
  dir.write("f_0.obj", two);
  dir.write("f_1.obj", "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const auto scene = dir.write("scene.json", R"({"frames": {"pattern": "f_%d.obj", "count": 2}})");
  const std::string binary = std::string(VPROXQ_BINARY) + " " + quote(scene);
  auto r = test::run_command("{ " + binary + " > " + quote(dir / "stdout.txt") + "; }");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("frame 1 has 1 objects"), std::string::npos) << r.output;
  EXPECT_EQ(slurp(dir / "stdout.txt"), "");
  // Frame 0 alone succeeds and prints its summary.
  r = test::run_command("{ " + binary + " --frames 0 > " + quote(dir / "stdout.txt") + "; }");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(slurp(dir / "stdout.txt").rfind("frame 0: 2 objects, 2 triangles", 0), 0u) << slurp(dir / "stdout.txt");
  // 1 block (512 or 1024 bytes, by the shell) below the summary of skirt-tiny's frames.
  r = test::run_command("{ ulimit -c 0; ulimit -f 1; " + std::string(VPROXQ_BINARY) + " " +
                        quote(kSamples / "skirt-tiny" / "scene.json") + " > " + quote(dir / "big.txt") + "; }");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("cannot write the summary to standard output: File too large"), std::string::npos)
      << r.output;
}

// Object names that are not valid UTF-8 are printed in the summary as the result files write
// them, with U+FFFD for each bad sequence.
TEST(Cli, TheSummaryPrintsNamesAsTheResultFilesWriteThem) {
  ScratchDir dir;
  const auto mesh = dir.write("names.obj", "o caf\xe9\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
                                           "o b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n");
  const auto r = vproxq(quote(mesh));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("caf\xef\xbf\xbd "), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find("caf\xe9"), std::string::npos) << r.output;
}

// A run killed without a chance to clean up (SIGKILL, the out-of-memory killer) leaves its
// temporaries; the next run into the same directory removes those of processes of this host
// that no longer exist, and nothing else.
TEST(Cli, StaleTemporariesOfDeadRunsAreRemoved) {
  char name[256] = {};
  ASSERT_EQ(::gethostname(name, sizeof name - 1), 0);
  std::string host;
  for (const char* c = name; *c != '\0'; ++c)
    if (std::isalnum(static_cast<unsigned char>(*c)) || *c == '.' || *c == '-') host += *c;
  if (host.empty()) host = "host";
  const pid_t child = ::fork();
  ASSERT_GE(child, 0);
  if (child == 0) ::_exit(0);
  ASSERT_EQ(::waitpid(child, nullptr, 0), child);  // `child` no longer exists
  const std::string dead = std::to_string(child), alive = std::to_string(::getpid());

  ScratchDir dir;
  const std::vector<std::string> stale = {".results.json.tmp-" + host + "-" + dead,
                                          ".results.h5.tmp-" + host + "-" + dead};
  const std::vector<std::string> kept = {".results.json.tmp-" + host + "-" + alive,
                                         ".results.h5.tmp-other-host-" + dead,
                                         ".results.h5.previous.tmp-" + host + "-" + dead,
                                         ".results.json.tmp-" + host + "-" + dead + "x", "notes.txt"};
  for (const auto& f : stale) dir.write("out/" + f, "partial\n");
  for (const auto& f : kept) dir.write("out/" + f, "keep\n");
  const auto r = vproxq(quote(kSamples / "two-cubes" / "scene.json") + " --frames 0:1 --quiet -o " + quote(dir / "out"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_TRUE(fs::exists(dir / "out" / "results.json"));
  for (const auto& f : stale) EXPECT_FALSE(fs::exists(dir / "out" / f)) << f;
  for (const auto& f : kept) EXPECT_TRUE(fs::exists(dir / "out" / f)) << f;
}

/// Runs `command` through /bin/sh with stdout and stderr on a pipe whose reading end is
/// already closed (a reader that went away) and SIGPIPE at its default action; returns the
/// status as a shell reports it (128 + the signal for a run ended by one).
int run_with_output_closed(const std::string& command) {
  int fds[2];
  if (::pipe(fds) != 0) return -1;
  ::close(fds[0]);
  const pid_t child = ::fork();
  if (child == 0) {
    ::signal(SIGPIPE, SIG_DFL);
    ::dup2(fds[1], 1);
    ::dup2(fds[1], 2);
    ::close(fds[1]);
    ::execl("/bin/sh", "sh", "-c", command.c_str(), static_cast<char*>(nullptr));
    ::_exit(127);
  }
  ::close(fds[1]);
  int status = 0;
  if (child < 0 || ::waitpid(child, &status, 0) != child) return -1;
  return WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
}

// With -o, a reader of stdout and stderr that goes away (`vproxq SCENE -o OUT 2>&1 | head`)
// does not end the run: it writes its files, with nothing left behind, and exits with its own
// code. The runs print on stderr from the start (a note on an unused option) and at the end
// ("wrote ..."). Without -o, the summary on stdout is the product, and SIGPIPE ends the run.
TEST(Cli, ARunWithOutputOutlivesAClosedTerminalPipe) {
  ScratchDir dir;
  const std::string run = std::string(VPROXQ_BINARY) + " " + quote(kSamples / "two-cubes" / "scene.json");
  const auto out = dir / "out";
  EXPECT_EQ(run_with_output_closed(run + " --grid 64 -o " + quote(out)), 0);
  ASSERT_TRUE(fs::exists(out / "results.json"));
  EXPECT_EQ(read_json(out / "results.json")["frames"].size(), 3u);
  for (const auto& e : fs::directory_iterator(out))
    EXPECT_TRUE(e.path().filename() == "results.json" || e.path().filename() == "results.h5") << e.path();
  // The run's own error code still comes back.
  EXPECT_EQ(run_with_output_closed(run + " --frames 9 -o " + quote(dir / "none")), 2);
  EXPECT_FALSE(fs::exists(dir / "none"));
  EXPECT_EQ(run_with_output_closed(run), 128 + SIGPIPE);
}

// A failed run removes the output directories it created (all of a nested -o path), and
// leaves an existing directory and what was in it alone.
TEST(Cli, FailedRunRemovesTheDirectoriesItCreated) {
  ScratchDir dir;
  const auto scene = dir.write("scene.json", R"({"frames": {"files": ["bad.obj"]}})");
  dir.write("bad.obj", "o a\nv 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  auto r = vproxq(quote(scene) + " -o " + quote(dir / "a" / "b" / "out") + " --quiet");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_FALSE(fs::exists(dir / "a"));

  dir.write("kept/note.txt", "mine\n");
  r = vproxq(quote(scene) + " -o " + quote(dir / "kept" / "new") + " --quiet");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_FALSE(fs::exists(dir / "kept" / "new"));
  EXPECT_TRUE(fs::exists(dir / "kept" / "note.txt"));
}

TEST(Cli, SceneFileErrors) {
  ScratchDir dir;
  auto r = vproxq(quote(dir / "missing.json"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("missing.json"), std::string::npos) << r.output;

  dir.write("a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
  const std::vector<std::pair<std::string, std::string>> bad = {
      {R"({"frames": {"files": ["a.obj"]}, "objcts": "meshes"})", "objcts"},
      {R"({"frames": {"pattern": "a_%d.obj", "first": 0, "count": -3}})", "count"},
      {R"({"frames": {"files": ["nope.obj"]}})", "nope.obj"},
      {R"({"frames": {"files": ["a.obj"]}, "objects": "pieces"})", "objects"},
      {R"({"frames": {"files": ["a.obj"]}, "grid": "big"})", "grid"},
      {R"({"frames": )", "scene.json"},
      {R"({"name": "no frames"})", "frames"},
  };
  for (const auto& [text, key] : bad) {
    SCOPED_TRACE(text);
    const auto scene = dir.write("scene.json", text);
    r = vproxq(quote(scene) + " --quiet");
    EXPECT_EQ(r.exit_code, 3) << r.output;
    EXPECT_NE(r.output.find(key), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("scene.json"), std::string::npos) << r.output;
  }
}

TEST(Cli, UnwritableOutputIsARuntimeError) {
  ScratchDir dir;
  const auto blocker = dir.write("file", "not a directory\n");
  const auto r = vproxq(quote(kSamples / "two-cubes" / "scene.json") + " -o " + quote(blocker / "out") + " --quiet");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("out"), std::string::npos) << r.output;
}

// Running out of memory (here: a 400 MB address-space limit against --grid 4096, which needs
// gigabytes) is a runtime error that says so and names the usual cause, and writes nothing.
/// Whether this is a VPROXQ_SANITIZE build (gcc defines the first, clang has the second).
#if defined(__SANITIZE_ADDRESS__)
constexpr bool kAddressSanitizer = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
constexpr bool kAddressSanitizer = true;
#else
constexpr bool kAddressSanitizer = false;
#endif
#else
constexpr bool kAddressSanitizer = false;
#endif

TEST(Cli, OutOfMemoryIsARuntimeErrorWithoutOutput) {
  if (kAddressSanitizer)
    GTEST_SKIP() << "AddressSanitizer (VPROXQ_SANITIZE) cannot start under ulimit -v: it reserves terabytes of shadow memory";
  ScratchDir dir;
  const auto out = dir / "out";
  const auto r = test::run_command("ulimit -v 400000; " + std::string(VPROXQ_BINARY) + " " +
                                   quote(kSamples / "skirt-tiny" / "scene.json") +
                                   " --voronoi=cpu --grid 4096 --frames 0:1 --quiet -o " + quote(out));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("out of memory"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("--grid"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(out / "results.json"));
  EXPECT_FALSE(fs::exists(out / "results.h5"));
}

// A write that fails (here: a file-size limit, as a full disk would) is a runtime error with a
// one-line message and no output; the HDF5 library's exit handler used to crash after it.
TEST(Cli, AFailedWriteIsARuntimeErrorWithoutOutput) {
  ScratchDir dir;
  const auto out = dir / "out";
  const auto r = test::run_command("ulimit -f 8; trap '' XFSZ; " + std::string(VPROXQ_BINARY) + " " +
                                   quote(kSamples / "blobs-small" / "scene.json") +
                                   " --queries distance,ccd,pd --quiet -o " + quote(out));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("File too large"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find('\n'), r.output.size() - 1) << "one line: " << r.output;
  EXPECT_FALSE(fs::exists(out));
}

TEST(Cli, FailureKeepsEarlierResultsIntact) {
  ScratchDir dir;
  const std::string tri = "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\no b\nv 0 0 1\nv 1 0 1\nv 0 1 1\nf 4 5 6\n";
  dir.write("f_0.obj", tri);
  dir.write("f_1.obj", tri);
  const auto scene = dir.write("scene.json", R"({"frames": {"pattern": "f_%d.obj", "first": 0, "count": 2}})");
  const auto out = dir / "out";
  auto r = vproxq(quote(scene) + " -o " + quote(out) + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string before = [&] { std::ifstream in(out / "results.json"); return std::string(std::istreambuf_iterator<char>(in), {}); }();
  dir.write("f_1.obj", "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n");
  r = vproxq(quote(scene) + " -o " + quote(out) + " --quiet");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  const std::string after = [&] { std::ifstream in(out / "results.json"); return std::string(std::istreambuf_iterator<char>(in), {}); }();
  EXPECT_EQ(before, after);
  EXPECT_TRUE(fs::exists(out / "results.h5"));
}

// A results.json that cannot be replaced (here a directory in its place) fails the run before
// anything is moved into place: no new results.h5 beside the old results.json, no temporaries.
TEST(Cli, AnOutputNameTakenByADirectoryFailsWithoutReplacingAnything) {
  ScratchDir dir;
  const auto scene = kSamples / "two-cubes" / "scene.json";
  const auto out = dir / "out";
  auto r = vproxq(quote(scene) + " -o " + quote(out) + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const std::string h5_before = slurp(out / "results.h5");
  fs::remove(out / "results.json");
  fs::create_directory(out / "results.json");
  r = vproxq(quote(scene) + " --queries distance,pd -o " + quote(out) + " --quiet");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("results.json"), std::string::npos) << r.output;
  EXPECT_EQ(slurp(out / "results.h5"), h5_before);
  for (const auto& entry : fs::directory_iterator(out))
    EXPECT_TRUE(entry.path().filename() == "results.h5" || entry.path().filename() == "results.json")
        << entry.path();

  // With no earlier results.h5, none is left behind.
  fs::remove(out / "results.h5");
  r = vproxq(quote(scene) + " -o " + quote(out) + " --quiet");
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_FALSE(fs::exists(out / "results.h5"));
}

TEST(Cli, SampleScenesEqualBruteForce) {
  for (const char* name : {"two-cubes", "blobs-small"}) {
    SCOPED_TRACE(name);
    ScratchDir dir;
    const auto scene = kSamples / name / "scene.json";
    const auto r = vproxq(quote(scene) + " -o " + quote(dir / "out") + " --quiet --threads 2");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    ASSERT_TRUE(fs::exists(dir / "out" / "results.h5"));
    expect_results_equal_brute_force(scene, dir / "out" / "results.json");
  }
}

TEST(Cli, TwoCubesFarCloseIntersecting) {
  ScratchDir dir;
  const auto r = vproxq(quote(kSamples / "two-cubes" / "scene.json") + " -o " + quote(dir / "out") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = read_json(dir / "out" / "results.json");
  ASSERT_EQ(j["frames"].size(), 3u);
  const double far = j["frames"][0]["distance"]["inter"][0]["distance"];
  const double close = j["frames"][1]["distance"]["inter"][0]["distance"];
  const double touching = j["frames"][2]["distance"]["inter"][0]["distance"];
  EXPECT_GT(far, close);
  EXPECT_GT(close, 0.0);
  EXPECT_EQ(touching, 0.0);
}

TEST(Cli, RandomScenesEqualBruteForce) {
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    SCOPED_TRACE("seed " + std::to_string(seed));
    ScratchDir dir;
    for (int k = 0; k < 3; ++k)
      write_obj(test::make_random_frame(seed * 10 + static_cast<std::uint64_t>(k), 8, 2.5, 1),
                dir / ("f_" + std::to_string(k) + ".obj"));
    const auto scene = dir.write("scene.json", R"({"frames": {"pattern": "f_%d.obj", "first": 0, "count": 3}})");
    const auto r = vproxq(quote(scene) + " -o " + quote(dir / "out") + " --quiet --threads 2");
    ASSERT_EQ(r.exit_code, 0) << r.output;
    expect_results_equal_brute_force(scene, dir / "out" / "results.json");
  }
}

TEST(Cli, RepeatedRunsAreIdenticalAndDiffDetectsChanges) {
  ScratchDir dir;
  const auto scene = quote(kSamples / "blobs-small" / "scene.json");
  auto r = vproxq(scene + " -o " + quote(dir / "a") + " --quiet --threads 1");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  r = vproxq(scene + " -o " + quote(dir / "b") + " --quiet --threads 2");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto a = dir / "a" / "results.json", b = dir / "b" / "results.json";
  r = vproxq("diff " + quote(a) + " " + quote(b));
  EXPECT_EQ(r.exit_code, 0) << r.output;

  // Perturb one distance: diff must fail and name the field; a tolerance accepts it.
  nlohmann::json j = read_json(b);
  const double d = j["frames"][2]["distance"]["inter"][1]["distance"];
  j["frames"][2]["distance"]["inter"][1]["distance"] = d * (1 + 1e-9);
  std::ofstream(dir / "c.json") << j.dump();
  r = vproxq("diff " + quote(a) + " " + quote(dir / "c.json"));
  EXPECT_EQ(r.exit_code, 1) << r.output;
  EXPECT_NE(r.output.find("frame 2"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("distance"), std::string::npos) << r.output;
  r = vproxq("diff " + quote(a) + " " + quote(dir / "c.json") + " --rtol 1e-6");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  // Or the member left out wherever it occurs; the output names what was ignored.
  r = vproxq("diff " + quote(a) + " " + quote(dir / "c.json") + " --ignore inter,intra --ignore points");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("identical (ignoring stats, version, settings, inter, intra, points)"), std::string::npos) << r.output;
  r = vproxq("diff " + quote(a) + " " + quote(dir / "c.json") + " --ignore intra");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  r = vproxq("diff " + quote(a) + " " + quote(dir / "c.json") + " --ignore=");
  EXPECT_EQ(r.exit_code, 2) << r.output;
  // An empty item is a usage error, as in --queries; a name given twice (or one always left
  // out) is listed once.
  for (const char* bad : {"--ignore inter,,intra", "--ignore inter,", "--ignore ,inter", "--ignore ''"}) {
    r = vproxq("diff " + quote(a) + " " + quote(dir / "c.json") + " " + bad);
    EXPECT_EQ(r.exit_code, 2) << bad << ": " << r.output;
    EXPECT_NE(r.output.find("usage error: --ignore"), std::string::npos) << bad << ": " << r.output;
  }
  r = vproxq("diff " + quote(a) + " " + quote(dir / "c.json") + " --ignore inter,stats --ignore inter");
  EXPECT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("identical (ignoring stats, version, settings, inter)\n"), std::string::npos) << r.output;
  // A subnormal tolerance is a finite number >= 0 too (accepted, and far too small here).
  r = vproxq("diff " + quote(a) + " " + quote(dir / "c.json") + " --atol=1e-310");
  EXPECT_EQ(r.exit_code, 1) << r.output;
  r = vproxq("diff " + quote(a) + " " + quote(dir / "missing.json"));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  r = vproxq("diff " + quote(a) + " " + quote(dir.path()));  // the output folder, not its file
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("is a directory, not a results file"), std::string::npos) << r.output;
  // The run's other file: named as such, and no raw binary byte on the terminal.
  r = vproxq("diff " + quote(dir / "a" / "results.h5") + " " + quote(a));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("results.h5' is an HDF5 file (results.h5); vproxq diff compares results.json files"),
            std::string::npos) << r.output;
  // Another binary file (a PNG's signature): the parser's message quotes its first byte, shown
  // as U+FFFD, not as the raw byte.
  std::ofstream(dir / "image.png", std::ios::binary) << "\x89PNG\r\n\x1a\n";
  r = vproxq("diff " + quote(dir / "image.png") + " " + quote(a));
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find("malformed results file"), std::string::npos) << r.output;
  EXPECT_EQ(r.output.find('\x89'), std::string::npos) << r.output;
}

TEST(Cli, FrameRangeAndSummary) {
  const auto scene = quote(kSamples / "two-cubes" / "scene.json");
  auto r = vproxq(scene + " --frames 1:3");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_EQ(r.output.find("frame 0:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("frame 1:"), std::string::npos) << r.output;
  EXPECT_NE(r.output.find("frame 2:"), std::string::npos) << r.output;
  ScratchDir dir;
  r = vproxq(scene + " --frames 2 -o " + quote(dir / "out") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = read_json(dir / "out" / "results.json");
  ASSERT_EQ(j["frames"].size(), 1u);
  EXPECT_EQ(j["frames"][0]["frame"].get<int>(), 2);
}

}  // namespace
}  // namespace vproxq

namespace vproxq {
namespace {

TEST(Generator, RegeneratesTheCommittedSampleSceneByteForByte) {
  ScratchDir dir;
  const auto r = run_command(std::string(VPROXQ_GEN_BINARY) +
                             " blobs --objects 12 --subdiv 1 --frames 6 --seed 1 --out " + quote(dir.path()));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto committed = kSamples / "blobs-small";
  EXPECT_EQ(slurp(dir / "scene.json"), slurp(committed / "scene.json"));
  for (int k = 0; k < 6; ++k) {
    char name[32];
    std::snprintf(name, sizeof name, "frames/blobs_%04d.obj", k);
    EXPECT_EQ(slurp(dir / name), slurp(committed / name)) << name;
  }
}

}  // namespace
}  // namespace vproxq

namespace vproxq {
namespace {

TEST(CliVoronoi, BackendsGiveIdenticalResultsEqualToBruteForce) {
  for (const char* name : {"two-cubes", "blobs-small"}) {
    SCOPED_TRACE(name);
    ScratchDir dir;
    const auto scene = kSamples / name / "scene.json";
    for (const char* backend : {"off", "cpu", "gpu"}) {
      const auto out = dir / backend;
      const auto r = vproxq(quote(scene) + " -o " + quote(out) + " --quiet --threads 2 --grid 48 --voronoi=" + backend);
      ASSERT_EQ(r.exit_code, 0) << backend << ": " << r.output;
      const auto j = read_json(out / "results.json");
      EXPECT_EQ(j["settings"]["voronoi"].get<std::string>(), backend);
      if (std::string(backend) != "off") {
        EXPECT_EQ(j["frames"][0]["stats"]["voronoi"]["grid"].size(), 3u);
        EXPECT_GT(j["frames"][0]["stats"]["voronoi"]["delta"].get<double>(), 0.0);
      }
      expect_results_equal_brute_force(scene, out / "results.json");
    }
    for (const char* backend : {"cpu", "gpu"}) {
      const auto r = vproxq("diff " + quote(dir / "off" / "results.json") + " " + quote(dir / backend / "results.json"));
      EXPECT_EQ(r.exit_code, 0) << backend << ": " << r.output;
    }
  }
}

TEST(CliVoronoi, WithoutEglAutoFallsBackToCpuAndGpuFails) {
  ScratchDir dir;
  const std::string env = "VPROXQ_EGL_LIBRARY=libvproxq-no-such-egl.so.1 ";
  const auto scene = quote(kSamples / "two-cubes" / "scene.json");
  auto r = run_command(env + std::string(VPROXQ_BINARY) + " " + scene + " --voronoi=auto -o " + quote(dir / "auto"));
  ASSERT_EQ(r.exit_code, 0) << r.output;
  EXPECT_NE(r.output.find("using --voronoi=cpu"), std::string::npos) << r.output;
  EXPECT_EQ(read_json(dir / "auto" / "results.json")["settings"]["voronoi"].get<std::string>(), "cpu");
  r = run_command(env + std::string(VPROXQ_BINARY) + " " + scene + " --voronoi=gpu -o " + quote(dir / "gpu"));
  EXPECT_EQ(r.exit_code, 4) << r.output;
  EXPECT_NE(r.output.find("libvproxq-no-such-egl.so.1"), std::string::npos) << r.output;
  EXPECT_FALSE(fs::exists(dir / "gpu" / "results.json"));
}

// An .off file given as the scene goes through the project's own OFF reader: a good one
// runs, one whose header declares more faces than it holds is an input error (exit 3, the
// file named, no results written), not an abort.
TEST(Cli, OffMeshFileAsTheScene) {
  ScratchDir dir;
  const auto good = dir.write("quad.off", "OFF\n4 1 0\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n");
  auto r = vproxq(quote(good) + " --queries distance -o " + quote(dir / "good") + " --quiet");
  ASSERT_EQ(r.exit_code, 0) << r.output;
  const auto j = read_json(dir / "good" / "results.json");
  ASSERT_EQ(j.at("frames").size(), 1u);

  const auto bad = dir.write("short.off", "OFF\n4 2 0\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n3 0 1 2\n");
  r = vproxq(quote(bad) + " --queries distance -o " + quote(dir / "bad") + " --quiet");
  EXPECT_EQ(r.exit_code, 3) << r.output;
  EXPECT_NE(r.output.find(bad.string() + ": line 2: the header declares 2 faces"), std::string::npos)
      << r.output;
  EXPECT_FALSE(fs::exists(dir / "bad")) << "a failed run leaves no results behind";
}

}  // namespace
}  // namespace vproxq
