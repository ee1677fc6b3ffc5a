#pragma once
// The project's own OFF reader (ASCII Geomview / Princeton Object File Format).
#include "io/mesh_reader.hpp"

#include <filesystem>

namespace vproxq::io_detail {

/// Reads an ASCII OFF file as one group named after the file stem, holding all its vertices
/// (in file order) and its faces (fan triangulated c0 ci ci+1, file order, the file's 0-based
/// indices; degenerate faces kept as they are).
///
/// Layout:
///   [ST][C][N]OFF [nv nf ne]   keyword; the counts may follow it on the same line
///   nv nf ne                   otherwise on the next line (ne, the edge count, is ignored)
///   x y z [extras]             nv vertex lines; extra numbers (colour, normal, texture
///                              coordinates of COFF, NOFF, STOFF, ...) are ignored
///   n i1 ... in [colour]       nf face lines; n >= 3; numbers after the n indices ignored
/// The keyword may be missing: a file whose first line is three non-negative integers is read
/// as if that line followed "OFF".
/// A `#` starts a comment running to the end of its line; blank and comment-only lines may be
/// anywhere. Line endings "\n" or "\r\n". Every vertex and every face is ONE line (as nearly
/// all writers do it), so the counts are checked against the number of data lines. A record
/// split over several lines is an error; a line holding several vertices reads as one vertex
/// with extras (usually then caught as too few lines for the counts). Lines after the nf-th
/// face line are ignored (as read_ply ignores data after the last element).
/// Not supported (InputError): OFF BINARY, 4OFF (4D vertices), nOFF (n-dimensional vertices).
///
/// Throws InputError "<file>: line <n>: <problem>" (or "<file>: <problem>" where no line
/// applies) for a missing or unreadable file, a malformed header or counts, counts larger than
/// the lines the file holds (checked before anything is allocated), non-numeric tokens,
/// vertex lines with fewer than 3 numbers, coordinates that are non-finite or out of range,
/// faces with fewer than 3 vertices or fewer indices than their count, and indices that are
/// not integers or not in [0, nv).
MeshGroup read_off(const std::filesystem::path& file);

}  // namespace vproxq::io_detail
