#include "sample_scenes/generators/scene_files.hpp"

#include "core/errors.hpp"

#include <nlohmann/json.hpp>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <system_error>
#include <utility>

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
  return scene_json_text(SceneDescription{name, pattern, count, "meshes", {}});
}

std::string scene_json_text(const SceneDescription& scene) {
  nlohmann::ordered_json j;
  j["name"] = scene.name;
  j["frames"] = {{"pattern", scene.pattern}, {"first", 0}, {"count", scene.count}};
  j["objects"] = scene.objects;
  if (!scene.statics.empty()) j["static"] = scene.statics;
  j["queries"] = {"distance"};
  return j.dump(2) + "\n";
}

int count_components(const std::vector<Face>& faces, std::size_t vertices) {
  std::vector<std::size_t> parent(vertices);
  for (std::size_t i = 0; i < vertices; ++i) parent[i] = i;
  auto find = [&](std::size_t i) {
    while (parent[i] != i) i = parent[i] = parent[parent[i]];
    return i;
  };
  std::vector<char> used(vertices, 0);
  for (const Face& f : faces) {
    const auto a = find(static_cast<size_t>(f[0]));
    used[static_cast<size_t>(f[0])] = used[static_cast<size_t>(f[1])] =
        used[static_cast<size_t>(f[2])] = 1;
    parent[find(static_cast<size_t>(f[1]))] = a;
    parent[find(static_cast<size_t>(f[2]))] = a;
  }
  int count = 0;
  for (std::size_t i = 0; i < vertices; ++i)
    if (used[i] && find(i) == i) ++count;
  return count;
}

namespace {

void make_directory(const std::filesystem::path& dir) {
  std::error_code ec;
  std::filesystem::create_directories(dir, ec);
  if (ec || !std::filesystem::is_directory(dir))
    throw RuntimeError("cannot create directory " + dir.string() +
                       (ec ? ": " + ec.message() : std::string(" (a file is in the way)")));
}

std::string frame_pattern(const std::string& name) { return "frames/" + name + "_%04d.obj"; }

}  // namespace

SceneWriter::SceneWriter(std::filesystem::path out, std::string name, std::string command,
                         int frames)
    : out_(std::move(out)), name_(std::move(name)), command_(std::move(command)), frames_(frames) {
  if (out_.empty()) throw UsageError("--out: the output folder name is empty");
  make_directory(out_ / "frames");
}

void SceneWriter::write_static(const std::string& file, const std::string& object,
                               const std::vector<V3>& positions, const std::vector<Face>& faces) {
  std::string text = "# " + command_ + ": static geometry\n";
  append_obj_object(text, object, positions, faces, 0);
  write_file_atomically(out_ / file, text);
  statics_.push_back(file);
  std::printf("wrote %s (%zu triangles, static)\n", (out_ / file).string().c_str(), faces.size());
}

void SceneWriter::begin_frame(int index, double time) {
  frame_ = index;
  char header[128];
  std::snprintf(header, sizeof header, ": frame %d of %d, t = %.17g\n", index, frames_, time);
  text_ = "# " + command_ + header;
  vertices_ = 0;
  triangles_ = 0;
  objects_ = 0;
  components_ = 0;
}

void SceneWriter::add_object(const std::string& name, const std::vector<V3>& positions,
                             const std::vector<Face>& faces) {
  append_obj_object(text_, name, positions, faces, vertices_);
  vertices_ += positions.size();
  triangles_ += static_cast<long long>(faces.size());
  ++objects_;
  components_ += count_components(faces, positions.size());
}

void SceneWriter::end_frame() {
  char file[256];
  std::snprintf(file, sizeof file, frame_pattern(name_).c_str(), frame_);
  const std::filesystem::path path = out_ / file;
  write_file_atomically(path, text_);
  std::printf("wrote %s (%d groups, %lld components, %lld triangles, %.0f kB)\n",
              path.string().c_str(), objects_, components_, triangles_, text_.size() / 1e3);
  std::fflush(stdout);
  text_.clear();
}

void SceneWriter::finish(const std::string& objects_mode) {
  const std::filesystem::path scene_file = out_ / "scene.json";
  write_file_atomically(
      scene_file,
      scene_json_text(SceneDescription{name_, frame_pattern(name_), frames_, objects_mode, statics_}));
  std::printf("wrote %s (%d frames)\n", scene_file.string().c_str(), frames_);
}

}  // namespace vproxq::gen
