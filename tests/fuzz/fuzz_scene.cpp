// Each input is a scene.json beside a few small mesh files of the harness's own (a.obj, two
// objects; frames/f_0000.obj to f_0002.obj, the same moving; b.ply, one triangle): opening it,
// checking its first 4 frame files as the CLI checks them, and loading those frames either
// throws InputError or succeeds. Seeds: the sample scenes' scene.json files, and scenes that
// name these files, e.g.
//   {"frames": {"pattern": "frames/f_%04d.obj", "first": 0, "count": 3}, "static": ["b.ply"]}
#include "core/errors.hpp"
#include "fuzz_support.hpp"
#include "io/scene_source.hpp"

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <string>

using namespace vproxq;

namespace {

void write_text(const std::filesystem::path& file, const std::string& text) {
  fuzz::write_file(file, text.data(), text.size());
}

std::string two_objects(double z) {
  return "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\nf 1 2 3\nf 1 2 4\ng second\nv 5 5 " + std::to_string(z) +
         "\nv 6 5 5\nv 5 6 5\nf 5 6 7\n";
}

}  // namespace

extern "C" int LLVMFuzzerInitialize(int*, char***) {
  const auto& dir = fuzz::scratch_dir();
  std::filesystem::create_directories(dir / "frames");
  write_text(dir / "a.obj", two_objects(5));
  for (int k = 0; k < 3; ++k) write_text(dir / "frames" / ("f_000" + std::to_string(k) + ".obj"), two_objects(5 + 0.1 * k));
  write_text(dir / "b.ply",
             "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
             "element face 1\nproperty list uchar int vertex_indices\nend_header\n0 0 3\n1 0 3\n0 1 3\n3 0 1 2\n");
  return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const auto file = fuzz::scratch_dir() / "scene.json";
  fuzz::write_file(file, data, size);
  try {
    // As the CLI opens it: the frame files are checked for the frames read.
    const SceneSource scene = SceneSource::open(file, FrameFileCheck::Deferred);
    scene.require_frames(0, 4);
    for (std::size_t k = 0; k < scene.frame_count() && k < 4; ++k) {
      const Frame frame = scene.load_frame(k);
      for (const Object& o : frame.objects)
        VPROXQ_FUZZ_CHECK(o.positions.size() == static_cast<std::size_t>(o.num_vertices()));
    }
  } catch (const InputError&) {
  }
  return 0;
}
