#pragma once
// The project's own Wavefront OBJ reader: double precision, the file's own vertex indices.
#include "io/mesh_reader.hpp"

#include <filesystem>
#include <vector>

namespace vproxq::io_detail {

/// What to do with the file's `o`/`g` groups.
enum class ObjGroups {
  Split,  ///< one MeshGroup per group that has faces (read_mesh_file's rule)
  Merge,  ///< one MeshGroup: every vertex and face of the file, in file order
};

/// Reads an OBJ file. Supported statements:
///   v x y z [w | r g b [a]]   position; the extra numbers (weight or vertex colour) are ignored
///   f c1 c2 c3 ...            corners `i`, `i/t`, `i//n`, `i/t/n`; 1-based indices, negative
///                             ones relative to the vertices read so far; positive ones may
///                             refer to vertices defined later in the file; polygons are fan
///                             triangulated (c1 ci ci+1), degenerate faces kept as they are
///   o name, g name            start a new group (each statement starts a new group, even
///                             with a name seen before; groups without faces are dropped)
/// Ignored: vt vn vp l p s usemtl mtllib, free-form curve/surface statements, comments
/// (`#` at the start of a line, or a token starting with `#` on v/f lines). Any other
/// statement is an error, and so is a `\` line continuation (not supported).
///
/// With Split: if at most one group has faces, the result is one group holding ALL vertices
/// (isolated ones kept, indices exactly the file's); otherwise each group with faces gets
/// the vertices its faces use, in file order, re-indexed. A group without a name is named
/// after the file stem, with "_<k>" (its position in the result) when the result has
/// several groups.
/// Throws InputError "<file>: line <n>: <problem>".
std::vector<MeshGroup> read_obj(const std::filesystem::path& file, ObjGroups groups);

}  // namespace vproxq::io_detail
