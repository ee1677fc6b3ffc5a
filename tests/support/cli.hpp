#pragma once
// End-to-end test helpers: run the built vproxq, read its results.json, write frames as OBJ.
#include "core/scene.hpp"
#include "support/process.hpp"

#include <nlohmann/json.hpp>

#include <filesystem>
#include <fstream>
#include <string>

namespace vproxq::test {

/// Runs the built CLI (VPROXQ_BINARY) with `args` (already quoted where needed).
inline ProcessResult vproxq(const std::string& args) {
  return run_command(std::string(VPROXQ_BINARY) + " " + args);
}

/// The whole file, bytes as they are ("" when it cannot be read).
inline std::string slurp(const std::filesystem::path& p) {
  std::ifstream in(p, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

inline nlohmann::json read_json(const std::filesystem::path& p) {
  std::ifstream in(p);
  return nlohmann::json::parse(in);
}

/// Writes a frame as one OBJ with an `o` group per object and 17 significant digits, so that
/// vproxq reads back exactly the same doubles and vertex indices.
inline void write_obj(const Frame& frame, const std::filesystem::path& file) {
  std::ofstream out(file);
  out.precision(17);
  Index base = 1;
  for (const Object& o : frame.objects) {
    out << "o " << o.name << "\n";
    for (const Vec3& p : o.positions) out << "v " << p.x() << " " << p.y() << " " << p.z() << "\n";
    for (const Face& f : o.topology->faces)
      out << "f " << f[0] + base << " " << f[1] + base << " " << f[2] + base << "\n";
    base += o.num_vertices();
  }
}

}  // namespace vproxq::test
