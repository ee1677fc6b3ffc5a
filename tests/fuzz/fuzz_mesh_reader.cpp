// Each input is read as an OBJ, a PLY and an OFF file (seed it with any mesh files, e.g.
// sample_scenes and tests/data/meshes): the readers either throw InputError or return groups
// whose faces index their own vertices, which split_components() then splits.
#include "core/errors.hpp"
#include "fuzz_support.hpp"
#include "io/mesh_reader.hpp"

#include <cstddef>
#include <cstdint>

using namespace vproxq;

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  for (const char* name : {"in.obj", "in.ply", "in.off"}) {
    const auto file = fuzz::scratch_dir() / name;
    fuzz::write_file(file, data, size);
    try {
      for (const MeshGroup& group : read_mesh_file(file)) {
        for (const Face& f : group.faces)
          for (Index v : f) VPROXQ_FUZZ_CHECK(v >= 0 && static_cast<std::size_t>(v) < group.positions.size());
        std::size_t faces = 0;
        for (const MeshGroup& piece : split_components(group)) faces += piece.faces.size();
        VPROXQ_FUZZ_CHECK(faces == group.faces.size());
      }
    } catch (const InputError&) {
    }
  }
  return 0;
}
