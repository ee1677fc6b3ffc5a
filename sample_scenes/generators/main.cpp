// vproxq-gen: deterministic scene generators for vproxq. The same arguments give the same
// bytes on every machine (own PRNG and sine, no FMA contraction; see det_math.hpp).
//
//   vproxq-gen blobs --objects 200 --frequency 3 --frames 5 --seed 1 --out bench-out/blobs-200
//
// writes OUT/frames/blobs_0000.obj ... (one OBJ per frame, one `o blobK` group per object,
// identical vertex indices in every frame) and OUT/scene.json.
#include "core/errors.hpp"
#include "sample_scenes/generators/blobs.hpp"
#include "sample_scenes/generators/scene_files.hpp"

#include <CLI/CLI.hpp>

#include <charconv>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <optional>
#include <string>

namespace fs = std::filesystem;
using namespace vproxq;
using namespace vproxq::gen;

namespace {

/// Upper bound on triangles per frame: beyond it OBJ frames run into gigabytes, and vproxq's
/// 32-bit ids are not far off.
constexpr long long kMaxTrianglesPerFrame = 50'000'000;

struct BlobsCommand {
  BlobsOptions options;
  std::optional<int> subdiv;     ///< --subdiv S, i.e. frequency 2^S
  std::optional<int> frequency;  ///< --frequency F
  fs::path out;
};

/// Accepts a whole number in [lo, hi], with a message that says which of the two is wrong.
CLI::Validator int_in(long long lo, long long hi) {
  const std::string range = "[" + std::to_string(lo) + ", " + std::to_string(hi) + "]";
  return CLI::Validator(
      [lo, hi, range](std::string& s) -> std::string {
        long long v = 0;
        const auto [end, err] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (s.empty() || err != std::errc() || end != s.data() + s.size())
          return "'" + s + "' is not a whole number";
        if (v < lo || v > hi) return s + " is outside " + range;
        return {};
      },
      "in " + range);
}

/// Accepts 0 .. 2^64-1 written in decimal digits only (no sign: "-1" would wrap around).
CLI::Validator seed_value() {
  return CLI::Validator(
      [](std::string& s) -> std::string {
        std::uint64_t v = 0;
        const auto [end, err] = std::from_chars(s.data(), s.data() + s.size(), v);
        if (s.empty() || err != std::errc() || end != s.data() + s.size())
          return "'" + s + "' is not a whole number in [0, 2^64-1]";
        return {};
      },
      "in [0, 2^64-1]");
}

/// The arguments that reproduce the files (no --out), written into every OBJ header.
std::string canonical_command(const BlobsCommand& cmd) {
  std::string s = "vproxq-gen blobs --objects " + std::to_string(cmd.options.objects);
  if (cmd.subdiv)
    s += " --subdiv " + std::to_string(*cmd.subdiv);
  else
    s += " --frequency " + std::to_string(cmd.options.frequency);
  s += " --frames " + std::to_string(cmd.options.frames);
  s += " --seed " + std::to_string(cmd.options.seed);
  return s;
}

void run_blobs(BlobsCommand cmd) {
  BlobsOptions& opt = cmd.options;
  if (cmd.out.empty()) throw UsageError("--out: the output folder name is empty");
  if (cmd.subdiv) opt.frequency = 1 << *cmd.subdiv;
  if (cmd.frequency) opt.frequency = *cmd.frequency;
  const long long tris_per_object = 20LL * opt.frequency * opt.frequency;
  if (tris_per_object * opt.objects > kMaxTrianglesPerFrame)
    throw UsageError(std::to_string(opt.objects) + " objects x " + std::to_string(tris_per_object) +
                     " triangles = " + std::to_string(tris_per_object * opt.objects) +
                     " triangles per frame; the limit is " + std::to_string(kMaxTrianglesPerFrame) +
                     " (use fewer --objects or a lower --subdiv/--frequency)");

  const BlobsScene scene = make_blobs(opt);
  const std::size_t nv = scene.sphere.directions.size();
  const std::size_t nt = scene.sphere.faces.size();
  const std::string command = canonical_command(cmd);
  const fs::path frames_dir = cmd.out / "frames";
  std::error_code ec;
  fs::create_directories(frames_dir, ec);
  if (ec || !fs::is_directory(frames_dir))
    throw RuntimeError("cannot create directory " + frames_dir.string() +
                       (ec ? ": " + ec.message() : std::string(" (a file is in the way)")));

  std::printf("%s: %d objects x %zu triangles = %lld triangles (%zu vertices each), %d frames\n",
              command.c_str(), opt.objects, nt, static_cast<long long>(nt) * opt.objects, nv,
              opt.frames);


  const std::string pattern = "frames/blobs_%04d.obj";
  for (int k = 0; k < opt.frames; ++k) {
    const double t = frame_time(opt, k);
    std::string text;
    text.reserve((nv * 3 * 25 + nt * 20) * static_cast<size_t>(opt.objects) + 256);
    char header[128];
    std::snprintf(header, sizeof header, ": frame %d of %d, t = %.17g\n", k, opt.frames, t);
    text += "# " + command + header;
    for (std::size_t b = 0; b < scene.blobs.size(); ++b)
      append_obj_object(text, "blob" + std::to_string(b), blob_positions(scene, b, t),
                        scene.sphere.faces, b * nv);
    char name[64];
    std::snprintf(name, sizeof name, pattern.c_str(), k);
    const fs::path file = cmd.out / name;
    write_file_atomically(file, text);
    std::printf("wrote %s (%.0f kB)\n", file.string().c_str(), text.size() / 1e3);
  }
  // Last, so that a scene.json is only there once all its frames are.
  const fs::path scene_file = cmd.out / "scene.json";
  write_file_atomically(scene_file, scene_json_text("blobs", pattern, opt.frames));
  std::printf("wrote %s (%d frames)\n", scene_file.string().c_str(), opt.frames);
}

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{
      "vproxq-gen: writes deterministic animated test scenes for vproxq (one OBJ per frame plus "
      "scene.json). The same arguments give byte-identical files on every machine."};
  app.require_subcommand(1, 1);

  BlobsCommand blobs;
  CLI::App* sub = app.add_subcommand(
      "blobs",
      "Deforming blobs (geodesic spheres with smooth radial waves, each its own radius) "
      "squeezed through a narrowing, swirling funnel: many are close, some touch or overlap. "
      "Frame k of F shows time k/(F-1) of the same animation.");
  sub->add_option("--objects", blobs.options.objects, "number of blobs")
      ->check(int_in(1, 1'000'000))
      ->capture_default_str();
  CLI::Option* subdiv =
      sub->add_option("--subdiv", blobs.subdiv,
                      "icosphere subdivision levels S: 20*4^S triangles per blob (1: 80, 2: 320)")
          ->check(int_in(0, 8));
  sub->add_option("--frequency", blobs.frequency,
                  "geodesic frequency F instead of --subdiv: 20*F^2 triangles per blob "
                  "(3: 180, the default, so 200 blobs give 36,000 triangles)")
      ->check(int_in(1, 256))
      ->excludes(subdiv);
  sub->add_option("--frames", blobs.options.frames, "number of frames")
      ->check(int_in(1, 100'000))
      ->capture_default_str();
  sub->add_option("--seed", blobs.options.seed, "random seed")
      ->check(seed_value())
      ->capture_default_str();
  sub->add_option("--out", blobs.out,
                  "output folder (created if missing; files of the same names are replaced)")
      ->required();

  try {
    app.parse(argc, argv);
    if (sub->parsed()) run_blobs(blobs);
    return exit_code::kOk;
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == static_cast<int>(CLI::ExitCodes::Success)) return app.exit(e);
    std::cerr << "vproxq-gen: error: " << e.what() << "\nRun 'vproxq-gen --help' or "
              << "'vproxq-gen blobs --help' for usage.\n";
    return exit_code::kUsage;
  } catch (const UsageError& e) {
    std::cerr << "vproxq-gen: error: " << e.what() << "\n";
    return exit_code::kUsage;
  } catch (const RuntimeError& e) {
    std::cerr << "vproxq-gen: error: " << e.what() << "\n";
    return exit_code::kRuntime;
  } catch (const std::exception& e) {
    std::cerr << "vproxq-gen: internal error: " << e.what() << "\n";
    return exit_code::kRuntime;
  }
}
