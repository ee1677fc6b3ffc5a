#pragma once
// Triangle meshes the simulated scenes are built from: cloth sheets and tubes, capsules,
// single-stroke letter tubes, a bowl, a funnel and flat boards. All deterministic (det_math).
#include "core/types.hpp"
#include "sample_scenes/generators/det_math.hpp"

#include <utility>
#include <vector>

namespace vproxq::gen {

struct Mesh {
  std::vector<V3> positions;
  std::vector<Face> faces;
};

/// Unique undirected edges (i < j) of the faces, sorted.
std::vector<std::pair<int, int>> mesh_edges(const std::vector<Face>& faces);

/// Flips every face when the mesh's signed volume is negative, so a closed mesh built with
/// consistently ordered faces ends up oriented outwards.
void orient_outwards(Mesh& mesh);

/// A rows x cols grid of vertices (vertex r * cols + c), two triangles per cell; with
/// wrap_columns the last column connects to the first (a tube), giving 2 (rows-1) cols
/// triangles, else 2 (rows-1)(cols-1). Positions are left empty: the caller places them.
std::vector<Face> grid_faces(int rows, int cols, bool wrap_columns);

/// A capsule around the z axis from z = 0 to z = length: `segments` vertices per ring,
/// `cap_rings` rings per hemisphere (besides the poles). Closed, oriented outwards.
Mesh capsule_mesh(double radius, double length, int segments, int cap_rings);

/// A spherical bowl: the part of the sphere (centre, radius) below z = rim_z, as an open
/// surface of `segments` x `rings` cells plus a fan at the bottom pole.
Mesh bowl_mesh(const V3& centre, double radius, double rim_z, int segments, int rings);

/// A funnel wall (open cone about the vertical axis through the origin) from (r_bottom,
/// z_bottom) to (r_top, z_top): `segments` around, `rings` along.
Mesh funnel_mesh(double r_bottom, double z_bottom, double r_top, double z_top, int segments,
                 int rings);

/// A flat rectangle origin + s u + t v, |s| <= half_u, |t| <= half_v, nu x nv cells.
Mesh board_mesh(const V3& origin, const V3& u, const V3& v, double half_u, double half_v, int nu,
                int nv);

/// The letter-like shapes: single pen strokes of the characters of "siggraph06" (a few are
/// simplified so one stroke draws them without crossing itself or turning back on itself, so
/// that no letter's tube intersects itself as it starts), in a box about 0.7 wide and 1 high,
/// z = 0.
inline constexpr int kGlyphCount = 10;
char glyph_char(int glyph);
/// A closed tube (elliptic cross-section: `half_width` in the letter's plane, `half_depth`
/// along z) swept along the stroke, `around` vertices per ring and `along` rings, with flat
/// fan caps on open strokes. 2 * around * along triangles either way. Centred on its
/// centroid, scaled by `scale`, oriented outwards.
Mesh glyph_mesh(int glyph, int around, int along, double scale, double half_width,
                double half_depth);

}  // namespace vproxq::gen
