#pragma once
// Writing generated scenes: OBJ frames and scene.json, each through a temporary file.
#include "core/types.hpp"
#include "sample_scenes/generators/det_math.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace vproxq::gen {

/// Writes `contents` to `path` via `path` + ".tmp" and a rename, so that nobody ever reads a
/// half-written file under the final name. Throws RuntimeError naming the file.
void write_file_atomically(const std::filesystem::path& path, const std::string& contents);

/// Appends one OBJ object: "o name", its vertices as "v x y z" with 17 significant digits
/// (doubles round-trip exactly), then its faces as "f a b c" (1-based, offset by the number
/// of vertices written before this object, `vertex_offset`).
void append_obj_object(std::string& out, const std::string& name, const std::vector<V3>& positions,
                       const std::vector<Face>& faces, std::size_t vertex_offset);

/// scene.json text for a frame sequence given by a printf pattern, split by OBJ groups.
std::string scene_json_text(const std::string& name, const std::string& pattern, int count);

/// What scene.json says about a generated scene.
struct SceneDescription {
  std::string name;
  std::string pattern;  ///< printf pattern of the frame files, relative to scene.json
  int count = 0;
  std::string objects = "meshes";    ///< or "components" (breaking objects)
  std::vector<std::string> statics;  ///< static mesh files, relative to scene.json
};
std::string scene_json_text(const SceneDescription& scene);

/// Writes a generated scene: static meshes, then the frames one by one
/// (OUT/frames/<name>_%04d.obj, one `o` group per object, a header line with the command
/// that reproduces it), then scene.json last, so that a scene.json is only there once all its
/// files are. Prints one line per file.
class SceneWriter {
 public:
  /// Creates OUT/frames. `command`: the generator arguments without --out.
  SceneWriter(std::filesystem::path out, std::string name, std::string command, int frames);

  /// Writes OUT/<file> (an OBJ with one group `object`) and lists it in scene.json.
  void write_static(const std::string& file, const std::string& object,
                    const std::vector<V3>& positions, const std::vector<Face>& faces);

  void begin_frame(int index, double time);
  void add_object(const std::string& name, const std::vector<V3>& positions,
                  const std::vector<Face>& faces);
  void end_frame();

  /// Writes scene.json with the given object mode ("meshes" or "components").
  void finish(const std::string& objects_mode);

 private:
  std::filesystem::path out_;
  std::string name_;
  std::string command_;
  int frames_ = 0;
  std::vector<std::string> statics_;
  std::string text_;        ///< the frame being built
  int frame_ = -1;
  std::size_t vertices_ = 0;     ///< vertices written in this frame so far (OBJ offset)
  long long triangles_ = 0;
  int objects_ = 0;
  long long components_ = 0;
};

/// Connected components of a face set over `vertices` vertices (vertices without faces are
/// not counted): what vproxq's "objects": "components" splits a group into.
int count_components(const std::vector<Face>& faces, std::size_t vertices);

}  // namespace vproxq::gen
