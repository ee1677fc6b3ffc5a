#include "sample_scenes/generators/geodesic_sphere.hpp"

#include <algorithm>
#include <array>
#include <map>
#include <stdexcept>
#include <utility>

namespace vproxq::gen {
namespace {

/// A grid point of the subdivided icosahedron as integer weights on icosahedron corners
/// (summing to the frequency), sorted by corner: the same point reached from two faces gets
/// the same key, so it becomes one vertex, with one position computed one way.
using PointKey = std::array<std::pair<int, int>, 3>;  // (corner, weight); unused: (-1, 0)

PointKey make_key(std::array<std::pair<int, int>, 3> w) {
  for (auto& cw : w)
    if (cw.second == 0) cw = {-1, 0};
  std::sort(w.begin(), w.end());
  return w;
}

}  // namespace

UnitSphereMesh geodesic_sphere(int frequency) {
  if (frequency < 1) throw std::invalid_argument("geodesic_sphere: frequency must be >= 1");

  // The regular icosahedron: 12 corners (0, +-1, +-phi) and cyclic permutations.
  const double phi = (1.0 + std::sqrt(5.0)) / 2.0;
  const std::array<V3, 12> corner = {{{-1, phi, 0}, {1, phi, 0}, {-1, -phi, 0}, {1, -phi, 0},
                                      {0, -1, phi}, {0, 1, phi}, {0, -1, -phi}, {0, 1, -phi},
                                      {phi, 0, -1}, {phi, 0, 1}, {-phi, 0, -1}, {-phi, 0, 1}}};
  std::array<std::array<int, 3>, 20> ico = {{{0, 11, 5}, {0, 5, 1},  {0, 1, 7},   {0, 7, 10},
                                             {0, 10, 11}, {1, 5, 9},  {5, 11, 4},  {11, 10, 2},
                                             {10, 7, 6}, {7, 1, 8},  {3, 9, 4},   {3, 4, 2},
                                             {3, 2, 6},  {3, 6, 8},  {3, 8, 9},   {4, 9, 5},
                                             {2, 4, 11}, {6, 2, 10}, {8, 6, 7},   {9, 8, 1}}};
  // Orient every face outwards (the table above already is; this keeps it so if edited).
  for (auto& f : ico) {
    const V3 a = corner[f[0]], b = corner[f[1]], c = corner[f[2]];
    if (dot(cross(b - a, c - a), a + b + c) < 0) std::swap(f[1], f[2]);
  }

  const int n = frequency;
  UnitSphereMesh mesh;
  std::map<PointKey, Index> vertex_of;
  auto vertex = [&](const std::array<int, 3>& f, int i, int j) -> Index {
    // Grid point i steps from corner f[0] towards f[1], j steps towards f[2].
    const PointKey key = make_key({{{f[0], n - i - j}, {f[1], i}, {f[2], j}}});
    auto it = vertex_of.find(key);
    if (it != vertex_of.end()) return it->second;
    V3 p;
    for (const auto& [c, w] : key)
      if (c >= 0) p = p + (static_cast<double>(w) / n) * corner[static_cast<size_t>(c)];
    const Index id = static_cast<Index>(mesh.directions.size());
    mesh.directions.push_back(normalized(p));
    vertex_of.emplace(key, id);
    return id;
  };

  mesh.faces.reserve(static_cast<size_t>(20 * n * n));
  for (const auto& f : ico) {
    for (int i = 0; i < n; ++i) {
      for (int j = 0; i + j < n; ++j) {
        mesh.faces.push_back({vertex(f, i, j), vertex(f, i + 1, j), vertex(f, i, j + 1)});
        if (i + j + 1 < n)
          mesh.faces.push_back({vertex(f, i + 1, j), vertex(f, i + 1, j + 1), vertex(f, i, j + 1)});
      }
    }
  }
  return mesh;
}

}  // namespace vproxq::gen
