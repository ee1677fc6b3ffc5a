#pragma once
// Meshes for the intra-object (self) proximity tests: a sheet folded over onto itself, and an
// irregular mesh with boundary, non-manifold edges, duplicate and degenerate triangles and
// isolated vertices.
#include "core/query/intra_distance.hpp"
#include "core/scene.hpp"
#include "support/expect_same.hpp"  // expect_same_intra, used with these meshes
#include "support/random_scene.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>

namespace vproxq::test {

inline Object make_object(std::vector<Vec3> positions, std::vector<Face> faces, const std::string& name) {
  auto topo = std::make_shared<Topology>();
  topo->num_vertices = static_cast<Index>(positions.size());
  topo->faces = std::move(faces);
  Object o;
  o.name = name;
  o.topology = std::move(topo);
  o.positions = std::move(positions);
  return o;
}

/// Directions of the sheets of make_aslant_sheet(): two in its plane (u, v) and its normal,
/// (1, 1, 1) normalised.
struct AslantFrame {
  Vec3 u = Vec3(1, -1, 0).normalized(), v = Vec3(1, 1, -2).normalized(), normal = Vec3(1, 1, 1).normalized();
};

/// A flat n x n grid sheet of unit squares (two triangles each) spanned by AslantFrame's u and
/// v from the origin, moved `offset` along its normal: lying aslant to every axis, so that
/// sheets side by side have overlapping boxes but stay apart along the diagonal (1, 1, 1).
inline Object make_aslant_sheet(int n, double offset, const std::string& name) {
  const AslantFrame w;
  std::vector<Vec3> p;
  for (int y = 0; y <= n; ++y)
    for (int x = 0; x <= n; ++x) p.push_back(x * w.u + y * w.v + offset * w.normal);
  std::vector<Face> faces;
  for (int y = 0; y < n; ++y)
    for (int x = 0; x < n; ++x) {
      const Index a = y * (n + 1) + x, b = a + 1, c = a + n + 1, d = c + 1;
      faces.push_back({a, b, d});
      faces.push_back({a, d, c});
    }
  return make_object(std::move(p), std::move(faces), name);
}

/// A regular nx x ny grid sheet of side `cell` (two triangles per square, diagonals alternating)
/// folded over onto itself around a half cylinder of radius gap / 2 at arc length `fold`: the
/// two layers face each other `gap` apart, so nearest non-adjacent triangles are across the
/// fold for gap below ~cell and within the layer otherwise. `jitter` (relative to cell) moves
/// every vertex randomly.
inline Object make_folded_sheet(Rng& rng, int nx, int ny, double cell, double gap, double jitter,
                                const std::string& name = "sheet") {
  const double r = gap / 2;
  const double fold = 0.5 * (nx * cell - M_PI * r);
  std::vector<Vec3> v;
  for (int j = 0; j <= ny; ++j)
    for (int i = 0; i <= nx; ++i) {
      const double s = i * cell, y = j * cell;
      Vec3 p;
      if (s <= fold) {
        p = Vec3(s, y, 0);
      } else if (s <= fold + M_PI * r) {
        const double t = (s - fold) / r;
        p = Vec3(fold + r * std::sin(t), y, r - r * std::cos(t));
      } else {
        p = Vec3(fold - (s - fold - M_PI * r), y, 2 * r);
      }
      p += cell * jitter * rng.vec3(-1, 1);
      v.push_back(p);
    }
  std::vector<Face> f;
  auto id = [&](int i, int j) { return static_cast<Index>(j * (nx + 1) + i); };
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      if ((i + j) % 2 == 0) {
        f.push_back({id(i, j), id(i + 1, j), id(i + 1, j + 1)});
        f.push_back({id(i, j), id(i + 1, j + 1), id(i, j + 1)});
      } else {
        f.push_back({id(i, j), id(i + 1, j), id(i, j + 1)});
        f.push_back({id(i + 1, j), id(i + 1, j + 1), id(i, j + 1)});
      }
    }
  return make_object(std::move(v), std::move(f), name);
}

/// A small open sheet (boundary edges) plus: three fins on one edge (non-manifold), a duplicate
/// triangle, a triangle with a repeated vertex, a zero-area (collinear) triangle, a triangle
/// crossing the sheet (intersecting non-adjacent pairs), and isolated vertices used by no face.
inline Object make_irregular_mesh(Rng& rng, const std::string& name = "irregular") {
  Object o = make_folded_sheet(rng, 6, 5, 0.2, 10.0, 0.15, name);  // gap 10: effectively flat
  auto topo = std::make_shared<Topology>(*o.topology);
  auto& v = o.positions;
  auto& f = topo->faces;
  auto add = [&](const Vec3& p) {
    v.push_back(p);
    return static_cast<Index>(v.size() - 1);
  };
  // Non-manifold: three more triangles on the edge (0, 1) of the sheet.
  const Index a = f[0][0], b = f[0][1];
  for (int k = 0; k < 3; ++k) f.push_back({a, b, add(Vec3(0.1, -0.1 - 0.05 * k, 0.1 + 0.1 * k))});
  const Face dup = f[7], rep = f[12];
  f.push_back(dup);                       // duplicate triangle
  f.push_back({rep[0], rep[0], rep[2]});  // repeated vertex
  const Index c0 = add(Vec3(0.3, 0.3, 0.05)), c1 = add(Vec3(0.5, 0.5, 0.05));
  f.push_back({c0, c1, add(Vec3(0.7, 0.7, 0.05))});  // collinear: zero area
  f.push_back({add(Vec3(0.45, 0.35, -0.2)), add(Vec3(0.55, 0.4, 0.2)), add(Vec3(0.5, 0.6, 0.1))});
  add(Vec3(0.4, 0.4, 0.01));  // isolated vertices
  add(Vec3(5, 5, 5));
  topo->num_vertices = static_cast<Index>(v.size());
  o.topology = std::move(topo);
  return o;
}

/// Closed tetrahedra, `count` of them in one object, `spacing` apart along x: with one, every
/// triangle shares a vertex with every other (no triangle has an answer).
inline Object make_tetrahedra(int count, double spacing, const std::string& name = "tets") {
  std::vector<Vec3> v;
  std::vector<Face> f;
  for (int k = 0; k < count; ++k) {
    const auto b = static_cast<Index>(v.size());
    const double x = spacing * k;
    v.insert(v.end(), {Vec3(x, 0, 0), Vec3(x + 1, 0, 0), Vec3(x, 1, 0), Vec3(x, 0, 1)});
    f.insert(f.end(), {{b, b + 2, b + 1}, {b, b + 1, b + 3}, {b, b + 3, b + 2}, {b + 1, b + 2, b + 3}});
  }
  return make_object(std::move(v), std::move(f), name);
}

/// Whether triangle t of o has a triangle sharing no vertex with it (brute force).
inline bool has_non_adjacent(const Object& o, Index t) {
  const auto& faces = o.topology->faces;
  const Face& a = faces[static_cast<size_t>(t)];
  for (const Face& b : faces) {
    bool shared = false;
    for (const Index x : a)
      for (const Index y : b) shared = shared || x == y;
    if (!shared) return true;
  }
  return false;
}

}  // namespace vproxq::test
