#pragma once
// Private to io/: reading a mesh file as a single object.
#include "io/mesh_reader.hpp"

#include <filesystem>

namespace vproxq::io_detail {

/// Reads `file` as ONE group named after the file stem: for OBJ every vertex and face of
/// the file in file order, whatever its o/g groups (so vertex ids stay the file's); for PLY
/// and OFF the file as read_mesh_file gives it; for assimp formats the meshes concatenated in
/// read_mesh_file's group order, each mesh's faces offset by the vertices before it.
/// Used for scene.json's per-object sequences, where each file is one object.
MeshGroup read_mesh_file_merged(const std::filesystem::path& file);

}  // namespace vproxq::io_detail
