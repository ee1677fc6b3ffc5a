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

}  // namespace vproxq::gen
