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
#include "sample_scenes/generators/sim_scenes.hpp"

#include <CLI/CLI.hpp>

#include <charconv>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <optional>
#include <string>
#include <tuple>
#include <vector>

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

/// A simulated scene's subcommand: its size options, plus --frames, --seed and --out.
struct SimCommand {
  std::string name;
  int* frames = nullptr;
  std::uint64_t* seed = nullptr;
  std::vector<std::pair<std::string, int*>> sizes;  ///< (option name, value), in order
  fs::path out;
  std::function<void(SceneWriter&)> generate;
  CLI::App* app = nullptr;
};

/// The arguments that reproduce the files (no --out), written into every OBJ header.
std::string canonical_command(const SimCommand& cmd) {
  std::string s = "vproxq-gen " + cmd.name;
  for (const auto& [option, value] : cmd.sizes) s += " --" + option + " " + std::to_string(*value);
  s += " --frames " + std::to_string(*cmd.frames) + " --seed " + std::to_string(*cmd.seed);
  return s;
}

void run_sim(const SimCommand& cmd) {
  const std::string command = canonical_command(cmd);
  std::printf("%s\n", command.c_str());
  const auto t0 = std::chrono::steady_clock::now();
  SceneWriter writer(cmd.out, cmd.name, command, *cmd.frames);
  cmd.generate(writer);
  const double s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
  std::printf("generated in %.1f s\n", s);
}

void add_sim_options(SimCommand& cmd,
                     const std::vector<std::tuple<std::string, int*, long long, long long,
                                                  std::string>>& sizes) {
  for (const auto& [option, value, lo, hi, help] : sizes) {
    cmd.app->add_option("--" + option, *value, help)->check(int_in(lo, hi))->capture_default_str();
    cmd.sizes.emplace_back(option, value);
  }
  cmd.app->add_option("--frames", *cmd.frames, "number of frames (1: the start state only)")
      ->check(int_in(1, 100'000))
      ->capture_default_str();
  cmd.app->add_option("--seed", *cmd.seed, "random seed")->check(seed_value())->capture_default_str();
  cmd.app->add_option("--out", cmd.out,
                      "output folder (created if missing; files of the same names are replaced)")
      ->required();
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

  // The paper's five benchmarks, simulated (position-based dynamics, see sim_scenes.hpp).
  SkirtOptions skirt;
  ClothBallOptions cloth_ball;
  BowlOptions bowl;
  FunnelOptions funnel;
  BreakingOptions breaking;
  std::vector<SimCommand> sims(5);
  sims[0].name = "skirt";
  sims[0].app = app.add_subcommand(
      "skirt",
      "Benchmark 1: a flared skirt of cloth (self-colliding) hanging from the waist of a body "
      "that twists and sways, over two swinging legs (capsules, written as objects). "
      "Default 12,000 cloth triangles + 2 legs, 40 frames over 2.5 s.");
  sims[0].frames = &skirt.frames;
  sims[0].seed = &skirt.seed;
  add_sim_options(sims[0], {{"segments", &skirt.segments, 8, 4096, "vertices around the skirt"},
                            {"rings", &skirt.rings, 3, 4096,
                             "vertex rings waist to hem: 2*segments*(rings-1) triangles"}});
  sims[0].generate = [&](SceneWriter& w) { generate_skirt(skirt, w); };

  sims[1].name = "cloth-ball";
  sims[1].app = app.add_subcommand(
      "cloth-ball",
      "Benchmark 2: a square cloth falling on a moving, spinning ball (an object) over the "
      "ground (static): it wraps the ball and folds onto itself. Default 15,138 cloth "
      "triangles + 320 ball triangles, 40 frames over 3 s.");
  sims[1].frames = &cloth_ball.frames;
  sims[1].seed = &cloth_ball.seed;
  add_sim_options(sims[1], {{"resolution", &cloth_ball.resolution, 3, 4096,
                             "cloth vertices per side: 2*(resolution-1)^2 triangles"}});
  sims[1].generate = [&](SceneWriter& w) { generate_cloth_ball(cloth_ball, w); };

  sims[2].name = "bowl";
  sims[2].app = app.add_subcommand(
      "bowl",
      "Benchmark 3: soft letter-like shapes (tubes swept along strokes of \"siggraph06\") "
      "falling into a bowl (static). Default 10 letters x 448 triangles, 40 frames over 3.5 s.");
  sims[2].frames = &bowl.frames;
  sims[2].seed = &bowl.seed;
  add_sim_options(sims[2], {{"objects", &bowl.objects, 1, 10'000, "number of letters"},
                            {"around", &bowl.around, 3, 256, "vertices around each tube"},
                            {"along", &bowl.along, 3, 4096,
                             "rings along each stroke: 2*around*along triangles per letter"}});
  sims[2].generate = [&](SceneWriter& w) { generate_bowl(bowl, w); };

  sims[3].name = "funnel";
  sims[3].app = app.add_subcommand(
      "funnel",
      "Benchmark 4: soft letters crowding through a funnel onto a ramp (funnel, ramp and floor "
      "static). Default 200 letters x 180 triangles, 40 frames over 3 s.");
  sims[3].frames = &funnel.frames;
  sims[3].seed = &funnel.seed;
  add_sim_options(sims[3], {{"objects", &funnel.objects, 1, 100'000, "number of letters"},
                            {"around", &funnel.around, 3, 256, "vertices around each tube"},
                            {"along", &funnel.along, 3, 4096,
                             "rings along each stroke: 2*around*along triangles per letter"}});
  sims[3].generate = [&](SceneWriter& w) { generate_funnel(funnel, w); };

  sims[4].name = "breaking";
  sims[4].app = app.add_subcommand(
      "breaking",
      "Benchmark 5: objects pre-cut into box pieces, dropped on the ground (static); each "
      "breaks into its pieces when it first touches the ground. One OBJ group per object, "
      "split into pieces by \"objects\": \"components\". Default 14 objects, 39 pieces, "
      "5,632 triangles before breaking, 40 frames over 2.5 s.");
  sims[4].frames = &breaking.frames;
  sims[4].seed = &breaking.seed;
  add_sim_options(sims[4], {{"objects", &breaking.objects, 1, 10'000, "number of objects"},
                            {"cells", &breaking.cells, 1, 64, "grid cells along a piece's side"}});
  sims[4].generate = [&](SceneWriter& w) { generate_breaking(breaking, w); };

  // An unknown first word: named, with the subcommands (CLI11 says only that one is required).
  if (argc >= 2 && argv[1][0] != '-') {
    std::string names;
    bool known = false;
    for (const CLI::App* c : app.get_subcommands([](CLI::App*) { return true; })) {
      known = known || c->get_name() == argv[1];
      names += (names.empty() ? "" : ", ") + c->get_name();
    }
    if (!known) {
      std::cerr << "vproxq-gen: error: unknown scene '" << argv[1] << "'; expected one of: " << names
                << "\nRun 'vproxq-gen --help' for usage.\n";
      return exit_code::kUsage;
    }
  }
  try {
    app.parse(argc, argv);
    for (const SimCommand& cmd : sims)
      if (cmd.app->parsed()) run_sim(cmd);
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
