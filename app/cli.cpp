#include "app/cli.hpp"

#include "app/check_ccd.hpp"
#include "app/config.hpp"
#include "core/errors.hpp"
#include "io/output.hpp"
#include "io/result_diff.hpp"
#include "io/scene_source.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <csignal>
#include <cstdlib>
#include <cstdio>
#include <cstring>
#include <exception>
#include <new>
#include <string>
#include <vector>

#include <signal.h>

namespace vproxq {
namespace {

const char* kDescription =
    "vproxq: exact proximity queries on animated triangle meshes.\n"
    "For every frame of SCENE (a scene.json or a single mesh file), in double precision and\n"
    "equal to brute force:\n"
    "  distance  each object's nearest other object (distance, closest triangles and points),\n"
    "            each triangle's nearest non-adjacent triangle of its own object, and every\n"
    "            intersecting triangle pair\n"
    "  ccd       every vertex-face and edge-edge pair that collides between this frame and the\n"
    "            next (vertices moving linearly), with its earliest time of impact\n"
    "  pd        the local penetration depth and direction of each intersecting object pair\n"
    "            and self-intersecting object\n"
    "Exit codes: 0 ok, 2 usage error, 3 input error, 4 runtime error.\n"
    "See also: vproxq diff A.json B.json (compare two result files),\n"
    "          vproxq check-ccd FILE.csv --type vf|ee (check CCD on ground-truth queries).";

/// Parses "A:B", "A:", ":B" or "A" (a single frame) into a FrameRange.
FrameRange parse_frame_range(const std::string& text) {
  auto parse_part = [&](const std::string& s) -> long {
    if (s.empty() || s.find_first_not_of("0123456789") != std::string::npos)
      throw UsageError("--frames " + text + ": expected A:B with non-negative integers (B exclusive)");
    // Past 10^15 no scene has that many frames, and std::stol would overflow.
    if (s.find_first_not_of('0') != std::string::npos && s.size() - s.find_first_not_of('0') > 15)
      throw UsageError("--frames " + text + ": frame number '" + s + "' is too large");
    return std::stol(s);
  };
  FrameRange r;
  const auto colon = text.find(':');
  if (colon == std::string::npos) {
    r.first = parse_part(text);
    r.last = *r.first + 1;
    return r;
  }
  const std::string a = text.substr(0, colon), b = text.substr(colon + 1);
  if (!a.empty()) r.first = parse_part(a);
  if (!b.empty()) r.last = parse_part(b);
  if (r.last && *r.last <= r.first.value_or(0))
    throw UsageError("--frames " + text + ": the range is empty (B is exclusive and must exceed A)");
  return r;
}

/// The items of the comma-separated values of a list option (--queries, diff --ignore), in
/// order. An empty item (`a,,b`) or value is a usage error, not a silent no-op: `noun` names
/// what a value lists, `expected` what its items may be.
std::vector<std::string> list_items(const std::vector<std::string>& values, const std::string& option,
                                    const std::string& noun, const std::string& expected) {
  std::vector<std::string> out;
  for (const std::string& text : values) {
    std::size_t start = 0;
    while (true) {
      const std::size_t comma = text.find(',', start);
      const std::string item = text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
      if (item.empty())
        throw UsageError(option + " '" + text + "': " + (text.empty() ? "no " + noun + " given" : "an empty item") +
                         "; expected " + expected);
      out.push_back(item);
      if (comma == std::string::npos) break;
      start = comma + 1;
    }
  }
  return out;
}

/// --queries' names. Repeats are usage errors, as they are in scene.json's "queries"; unknown
/// names are checked with the scene's list.
std::vector<std::string> parse_query_list(const std::vector<std::string>& values) {
  const std::vector<std::string> items =
      list_items(values, "--queries", "query", "comma-separated names from: " + query_names_list());
  for (auto it = items.begin(); it != items.end(); ++it)
    if (std::find(items.begin(), it, *it) != it) throw UsageError("--queries: '" + *it + "' is given twice");
  return items;
}

/// `vproxq diff --ignore`'s member names; a name given twice counts once.
std::vector<std::string> parse_key_list(const std::vector<std::string>& values) {
  std::vector<std::string> out;
  for (const std::string& item : list_items(values, "--ignore", "key", "comma-separated member names"))
    if (std::find(out.begin(), out.end(), item) == out.end()) out.push_back(item);
  return out;
}

/// An option value that must be a whole number in [lo, hi]: the message names the range and
/// the value given (CLI11's own range checks print the type's limits, e.g. DBL_MAX in full).
CLI::Validator whole_number(long lo, long hi, const std::string& meaning) {
  return CLI::Validator(
      [=](std::string& value) -> std::string {
        const std::string expect = "expected a whole number from " + std::to_string(lo) + " to " +
                                   std::to_string(hi) + " (" + meaning + "), got '" + value + "'";
        const bool digits = !value.empty() && value.size() <= 18 &&
                            value.find_first_not_of("0123456789") == std::string::npos;
        if (!digits) return expect;
        const long v = std::stol(value);
        return v < lo || v > hi ? expect : std::string();
      },
      "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
}

/// A tolerance: a finite number >= 0 (NaN would make every number differ, inf none).
CLI::Validator tolerance() {
  return CLI::Validator(
      [](std::string& value) -> std::string {
        const std::string expect = "expected a finite number >= 0, got '" + value + "'";
        // strtod, not stod: stod throws on values that underflow to subnormals (1e-310).
        if (value.empty() || std::isspace(static_cast<unsigned char>(value[0]))) return expect;
        char* end = nullptr;
        const double v = std::strtod(value.c_str(), &end);
        if (end != value.c_str() + value.size() || !std::isfinite(v) || v < 0) return expect;
        return {};
      },
      ">= 0");
}

/// The largest --threads: more threads than this only cost memory and start-up time, and
/// tens of thousands fail to start.
constexpr long kMaxThreads = 1024;

int report(const char* kind, const std::exception& e, int code) {
  // A message may quote bytes of an input file (a line of a mesh, a scene's text): shown as
  // valid UTF-8, as `diff` shows a parser's message and the result files write names, so that
  // stray bytes of a binary or Latin-1 file cannot garble the terminal.
  std::fprintf(stderr, "vproxq: %s: %s\n", kind, valid_utf8(e.what()).c_str());
  return code;
}

/// Runs `body`, mapping the error kinds to their exit codes.
/// Said after "out of memory" (set by the main command: a coarser --grid helps only when a
/// Voronoi backend runs).
const char* g_out_of_memory_hint = "";

template <typename F>
int guarded(F&& body) {
  try {
    return body();
  } catch (const UsageError& e) {
    return report("usage error", e, exit_code::kUsage);
  } catch (const InputError& e) {
    return report("input error", e, exit_code::kInput);
  } catch (const RuntimeError& e) {
    return report("error", e, exit_code::kRuntime);
  } catch (const std::bad_alloc&) {
    std::fprintf(stderr, "vproxq: error: out of memory (std::bad_alloc)%s\n", g_out_of_memory_hint);
    return exit_code::kRuntime;
  } catch (const std::exception& e) {
    return report("error", e, exit_code::kRuntime);
  }
}

int parse_or_exit(CLI::App& app, int argc, char** argv, bool& done) {
  done = false;
  // CLI11 reads `--name=` (nothing after the '=') as `--name` and takes the next argument as
  // its value: `--queries= SCENE` would then report SCENE missing, or an unknown query '-q'.
  for (int i = 1; i < argc; ++i) {
    const std::string arg = argv[i];
    if (arg == "--") break;
    if (arg.size() > 3 && arg.compare(0, 2, "--") == 0 && arg.back() == '=' && arg.find('=') == arg.size() - 1) {
      done = true;
      std::fprintf(stderr, "vproxq: usage error: %s has no value\nRun with --help for the options.\n",
                   arg.substr(0, arg.size() - 1).c_str());
      return exit_code::kUsage;
    }
    // The short form takes its value after a space or directly (-o OUT, -oOUT): `-o=OUT` would
    // write into a directory named "=OUT".
    if (arg == "-o=") {
      done = true;
      std::fprintf(stderr, "vproxq: usage error: -o= has no value: write -o OUT, -oOUT or --output=OUT\nRun with --help for the options.\n");
      return exit_code::kUsage;
    }
    if (arg.compare(0, 3, "-o=") == 0) {
      done = true;
      std::fprintf(stderr, "vproxq: usage error: %s: write -o %s or --output=%s (a directory whose name starts with '=': -o ./%s)\nRun with --help for the options.\n",
                   arg.c_str(), arg.substr(3).c_str(), arg.substr(3).c_str(), arg.substr(2).c_str());
      return exit_code::kUsage;
    }
  }
  try {
    app.parse(argc, argv);
  } catch (const CLI::CallForHelp& e) {
    done = true;
    return app.exit(e);
  } catch (const CLI::CallForAllHelp& e) {
    done = true;
    return app.exit(e);
  } catch (const CLI::CallForVersion& e) {
    done = true;
    return app.exit(e);
  } catch (const CLI::ParseError& e) {
    done = true;
    // CLI11 says "--grid: At Most 1 required but received 2" for an option of one value given
    // more than once.
    const std::string message = e.what();
    const std::string at_most = ": At Most 1 required but received ";
    const std::size_t at = message.find(at_most);
    if (at != std::string::npos && at > 0)
      std::fprintf(stderr, "vproxq: usage error: %s is given %s times; it takes one value\nRun with --help for the options.\n",
                   message.substr(0, at).c_str(), message.substr(at + at_most.size()).c_str());
    else
      std::fprintf(stderr, "vproxq: usage error: %s\nRun with --help for the options.\n", message.c_str());
    return exit_code::kUsage;
  }
  return 0;
}

int diff_main(int argc, char** argv) {
  CLI::App app{"vproxq diff: compare two results.json files, ignoring \"stats\", \"version\" and "
               "\"settings\".\nExit codes: 0 equal (within tolerance), 1 different, 2 usage "
               "error, 3 input error.", "vproxq diff"};
  std::string a, b;
  DiffOptions opts;
  app.add_option("A", a, "first results.json")->required();
  app.add_option("B", b, "second results.json")->required();
  app.add_option("--rtol", opts.rtol, "relative tolerance for numbers (default 0)")
      ->check(tolerance());
  app.add_option("--atol", opts.atol, "absolute tolerance for numbers (default 0)")
      ->check(tolerance());
  std::vector<std::string> ignore;
  app.add_option("--ignore", ignore,
                 "a member name to leave out wherever it occurs, e.g. a key added in a later version "
                 "(repeatable; comma-separated lists too)")
      ->option_text("KEY[,KEY...]");
  app.set_version_flag("--version", std::string("vproxq ") + VPROXQ_VERSION);
  bool done = false;
  const int code = parse_or_exit(app, argc, argv, done);
  if (done) return code;
  return guarded([&] {
    opts.ignore = parse_key_list(ignore);
    const DiffOutcome out = diff_result_files(a, b, opts);
    if (out.equal) {
      std::vector<std::string> listed = {"stats", "version", "settings"};
      for (const std::string& key : opts.ignore)
        if (std::find(listed.begin(), listed.end(), key) == listed.end()) listed.push_back(key);
      std::string ignored;
      for (const std::string& key : listed) ignored += (ignored.empty() ? "" : ", ") + key;
      std::printf("identical (ignoring %s)\n", ignored.c_str());
      return exit_code::kOk;
    }
    std::printf("different: %s\n", out.first_difference.c_str());
    return exit_code::kDifferent;
  });
}

int check_ccd_main(int argc, char** argv) {
  CLI::App app{"vproxq check-ccd: run the elementary CCD test on every query of a ground-truth "
               "file (8 rows of rational coordinates per query, last column the truth) and "
               "count the disagreements.\nExit codes: 0 no false negative, 1 false negatives "
               "found, 2 usage error, 3 input error.", "vproxq check-ccd"};
  std::string file, type;
  app.add_option("FILE", file, "query file (.csv)")->required();
  app.add_option("--type", type, "vf (vertex-face) or ee (edge-edge)")
      ->required()
      ->check(CLI::IsMember({"vf", "ee"}));
  app.set_version_flag("--version", std::string("vproxq ") + VPROXQ_VERSION);
  bool done = false;
  const int code = parse_or_exit(app, argc, argv, done);
  if (done) return code;
  return guarded([&] {
    const CheckCcdSummary s = check_ccd_file(file, type);
    std::printf("%s\n", format_check_ccd_summary(s).c_str());
    return s.false_negatives > 0 ? exit_code::kDifferent : exit_code::kOk;
  });
}

}  // namespace

int cli_main(int argc, char** argv) {
  if (argc >= 2 && std::strcmp(argv[1], "diff") == 0) return diff_main(argc - 1, argv + 1);
  if (argc >= 2 && std::strcmp(argv[1], "check-ccd") == 0)
    return check_ccd_main(argc - 1, argv + 1);

  CLI::App app{kDescription, "vproxq"};
  Config config;
  std::string frames;
  app.add_option("SCENE", config.scene_path, "scene.json, or a mesh file (a one-frame scene)")
      ->required();
  // Values split here, not by CLI11: its list splitting took the next argument when the value
  // had no item (`--queries=, SCENE`), and dropped empty items and repeats without a word.
  // The option may be given more than once; its lists are joined.
  std::vector<std::string> queries;
  app.add_option("--queries", queries,
                 "comma-separated queries to run (default: the scene's \"queries\", else "
                 "distance). Valid: " + query_names_list())
      ->allow_extra_args(false)
      ->option_text("Q[,Q...]");
  app.add_option("-o,--output", config.output_dir,
                 "write OUT/results.json and OUT/results.h5 (default: print a summary)")
      ->check([](const std::string& dir) { return dir.empty() ? std::string("the output directory must not be empty") : std::string(); });
  app.add_option("--frames", frames, "frame range A:B (0-based, B exclusive; A: or :B or A)");
  app.add_option("--voronoi", config.voronoi,
                 "Stage II (discrete Voronoi culling) backend: gpu (OpenGL compute in a headless "
                 "EGL context), cpu (the same algorithm on the CPU), off (AABB culling only), "
                 "auto (gpu on a hardware GPU, else cpu). Default: off. Results are identical.")
      ->check(CLI::IsMember({"off", "cpu", "gpu", "auto"}));
  app.add_option("--grid", config.grid,
                 "Voronoi grid of the distance queries: cells along the longest axis of the scene "
                 "box (default: the scene's \"grid\", else per query: 4*cbrt(triangles) clamped "
                 "to [32, 256] for the inter-object distance, sqrt(triangles) clamped to [32, 512] "
                 "but cells no smaller than 0.7 median triangle for the intra-object distance)")
      ->check(whole_number(1, kMaxGridResolution, "cells along the longest axis"));
  app.add_option("--ccd-grid", config.ccd_grid,
                 "CCD's Stage II grid: cells along the longest axis of the swept box of the "
                 "triangles it voxelizes, coarsened where they would cover thousands of voxels "
                 "each (default: a cell from the triangles' sizes and motion)")
      ->check(whole_number(1, kMaxGridResolution, "cells along the longest axis"));
  app.add_option("--device", config.device, "EGL device index for --voronoi=gpu (default: first hardware device)")
      ->check(whole_number(0, 1023, "an EGL device index"));
  std::string self;
  app.add_option("--self", self,
                 "the distance query's intra-object (\"self\") part: on, or off for the "
                 "inter-object distance and the intersecting pairs alone (default: the scene's "
                 "\"self\", else on)")
      ->check(CLI::IsMember({"on", "off"}));
  app.add_option("--threads", config.threads, "worker threads (default 0: all cores)")
      ->check(whole_number(0, kMaxThreads, "0: all cores"));
  app.add_flag("-q,--quiet", config.quiet, "no progress or summary on the terminal");
  app.set_version_flag("--version", std::string("vproxq ") + VPROXQ_VERSION);
  bool done = false;
  const int code = parse_or_exit(app, argc, argv, done);
  if (done) return code;
  return guarded([&] {
    if (!frames.empty()) config.frames = parse_frame_range(frames);
    if (app.count("--self") > 0) config.self = self == "on";
    if (app.count("--queries") > 0) config.queries = parse_query_list(queries);
    g_out_of_memory_hint = config.voronoi == "off" ? "" : "; a coarser --grid or --ccd-grid (or --voronoi=off) needs less";
    // With -o the results files are the run's product, and stdout and stderr carry only notes
    // and progress: a reader that goes away (`vproxq SCENE -o OUT 2>&1 | head -3`) must not end
    // the run half-way by SIGPIPE. Ignored, a write to the closed pipe fails and is dropped; the
    // run writes its files and exits with its own code. Without -o the summary on stdout is the
    // product, and SIGPIPE ends the run as it ends any filter (no files are written then).
    if (!config.output_dir.empty()) std::signal(SIGPIPE, SIG_IGN);
    // A write past the file-size limit (`ulimit -f`) fails with EFBIG and is reported like any
    // failed write (exit 4), for the summary on stdout as for the result files (io/output.cpp),
    // instead of ending the run by SIGXFSZ. A signal the caller ignores or handles is left so.
    struct sigaction xfsz {};
    if (::sigaction(SIGXFSZ, nullptr, &xfsz) == 0 && !(xfsz.sa_flags & SA_SIGINFO) && xfsz.sa_handler == SIG_DFL)
      std::signal(SIGXFSZ, SIG_IGN);
    // Options that the chosen backend does not use: said once, so that a sweep over --grid
    // with the default --voronoi=off does not silently measure the same run again and again.
    if (!config.quiet && config.voronoi == "off" && config.grid > 0)
      std::fprintf(stderr, "vproxq: note: --grid has no effect with --voronoi=off\n");
    if (!config.quiet && config.voronoi == "off" && config.ccd_grid > 0)
      std::fprintf(stderr, "vproxq: note: --ccd-grid has no effect with --voronoi=off\n");
    if (!config.quiet && config.device >= 0 && (config.voronoi == "off" || config.voronoi == "cpu"))
      std::fprintf(stderr, "vproxq: note: --device has no effect with --voronoi=%s\n", config.voronoi.c_str());
    run(config);
    return exit_code::kOk;
  });
}

}  // namespace vproxq
