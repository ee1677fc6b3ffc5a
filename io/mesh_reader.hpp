#pragma once
// Reading one mesh file into named groups of triangles, keeping the file's own indices.
#include "core/mesh/topology.hpp"
#include "core/types.hpp"

#include <filesystem>
#include <string>
#include <vector>

namespace vproxq {

/// One mesh of a file (an OBJ o/g group, a PLY or OFF file, an assimp mesh): vertices in file order
/// (only those its faces use, when the file holds several groups) and faces re-indexed into them.
struct MeshGroup {
  std::string name;
  std::vector<Vec3> positions;
  std::vector<Face> faces;
  /// Whether this is the only mesh of its file that the file gives no name of its own (`name`
  /// is then made from the file's name). See ComponentOrigin.
  bool file_named = false;
  /// Set by split_components(): the mesh this component was cut from (core/mesh/topology.hpp).
  ComponentOrigin origin;
};

/// Reads OBJ, PLY (ASCII and binary) and ASCII OFF with the project's own index-preserving,
/// double precision readers; other formats through assimp (float precision, see README). The
/// own readers fan-triangulate polygons and do no welding, no reordering and no removal of
/// degenerate faces; through assimp, polygons are triangulated by assimp and STL corners at one
/// position are welded (io/assimp_reader.cpp).
/// Throws InputError naming the file and the problem.
std::vector<MeshGroup> read_mesh_file(const std::filesystem::path& file);

/// Splits one group into its connected components (faces sharing a vertex), in order of
/// their first face; each component keeps its vertices in file order and records them, as
/// indices among the group's vertices, in its origin.
std::vector<MeshGroup> split_components(const MeshGroup& group);

}  // namespace vproxq
