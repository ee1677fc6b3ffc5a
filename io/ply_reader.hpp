#pragma once
// The project's own PLY reader (ascii, binary_little_endian, binary_big_endian).
#include "io/mesh_reader.hpp"

#include <filesystem>

namespace vproxq::io_detail {

/// Reads a PLY file as one group named after the file stem, holding all its vertices (in file
/// order) and its faces (fan triangulated, file order, file indices).
/// - `vertex` element: x, y, z of any scalar type, converted to double (a binary float or
///   double is kept exactly; an ascii value of an integer type must be written as an integer, and
///   integer values are not checked against their type's range).
///   Other vertex properties, lists included, are skipped.
/// - `face` element: the list `vertex_indices` (or `vertex_index`) with any integer count and
///   index types; other face properties are skipped. No `face` element: no faces.
/// - Any other element is skipped record by record (lists by their counts).
/// In an ascii file, anything but whitespace after the last declared element is an error (the
/// counts do not describe the data); a binary file's trailing bytes are ignored.
/// Throws InputError "<file>: <problem>" for a malformed header (an element or a property
/// declared twice, triangle strips), truncated or malformed data,
/// out-of-range indices, faces with fewer than 3 vertices, non-finite coordinates.
MeshGroup read_ply(const std::filesystem::path& file);

}  // namespace vproxq::io_detail
