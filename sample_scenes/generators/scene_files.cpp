#include "sample_scenes/generators/scene_files.hpp"

#include "core/errors.hpp"

#include <nlohmann/json.hpp>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <system_error>

namespace vproxq::gen {

void write_file_atomically(const std::filesystem::path& path, const std::string& contents) {
  std::filesystem::path tmp = path;
  tmp += ".tmp";
  {
    std::ofstream f(tmp, std::ios::binary | std::ios::trunc);
    if (!f) throw RuntimeError("cannot create " + tmp.string() + ": " + std::strerror(errno));
    f.write(contents.data(), static_cast<std::streamsize>(contents.size()));
    f.close();
    if (!f) {
      std::error_code ignored;
      std::filesystem::remove(tmp, ignored);
      throw RuntimeError("cannot write " + tmp.string() + " (disk full?)");
    }
  }
  std::error_code ec;
  std::filesystem::rename(tmp, path, ec);
  if (ec) {
    std::error_code ignored;
    std::filesystem::remove(tmp, ignored);
    throw RuntimeError("cannot rename " + tmp.string() + " to " + path.string() + ": " +
                       ec.message());
  }
}

void append_obj_object(std::string& out, const std::string& name, const std::vector<V3>& positions,
                       const std::vector<Face>& faces, std::size_t vertex_offset) {
  char line[128];
  out += "o ";
  out += name;
  out += '\n';
  for (const V3& p : positions) {
    std::snprintf(line, sizeof line, "v %.17g %.17g %.17g\n", p.x, p.y, p.z);
    out += line;
  }
  for (const Face& f : faces) {
    const std::size_t first = vertex_offset + 1;  // OBJ indices are 1-based
    std::snprintf(line, sizeof line, "f %zu %zu %zu\n", first + static_cast<size_t>(f[0]),
                  first + static_cast<size_t>(f[1]), first + static_cast<size_t>(f[2]));
    out += line;
  }
}

std::string scene_json_text(const std::string& name, const std::string& pattern, int count) {
  nlohmann::ordered_json j;
  j["name"] = name;
  j["frames"] = {{"pattern", pattern}, {"first", 0}, {"count", count}};
  j["objects"] = "meshes";
  j["queries"] = {"distance"};
  return j.dump(2) + "\n";
}

}  // namespace vproxq::gen
