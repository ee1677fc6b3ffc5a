#pragma once
// Mesh formats other than OBJ and PLY, through assimp. No assimp header appears here.
#include "io/mesh_reader.hpp"

#include <filesystem>
#include <vector>

namespace vproxq::io_detail {

/// Reads `file` with assimp, post-processing with aiProcess_Triangulate only: no vertex
/// welding (aiProcess_JoinIdenticalVertices) or any other position-dependent step, so the
/// file's own vertex indices survive.
/// Each mesh reference in the node hierarchy is one group (a mesh used by one node, the
/// usual case, is one group; an instanced mesh gives one group per instance), with the
/// nodes' transforms applied in double precision. Meshes without faces are dropped.
/// Precision: assimp stores positions as float (ai_real), so coordinates carry float32
/// rounding; OBJ and PLY use the project's own double-precision readers instead.
/// Group names: the mesh's name, else the node's, else the file stem ("_<k>" when several).
/// Throws InputError "<file>: assimp: <assimp's error string>", or naming the problem
/// (points or lines in a mesh, non-finite coordinate).
std::vector<MeshGroup> read_with_assimp(const std::filesystem::path& file);

}  // namespace vproxq::io_detail
