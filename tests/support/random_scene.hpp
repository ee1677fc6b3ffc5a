#pragma once
// Seeded random frames for tests: small deformed closed meshes placed close together, some
// touching, some overlapping, some exact copies (ties).
#include "core/scene.hpp"
#include "support/rng.hpp"

#include <algorithm>
#include <cmath>
#include <map>
#include <cstdint>
#include <memory>
#include <random>
#include <string>

namespace vproxq::test {

/// An octahedron subdivided `levels` times and pushed onto a sphere of radius r, then each
/// vertex jittered radially by up to `jitter` * r.
inline Object make_blob(Rng& rng, const Vec3& center, double r, int levels, double jitter,
                        const std::string& name) {
  std::vector<Vec3> v = {{1, 0, 0}, {-1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}, {0, 0, -1}};
  std::vector<Face> f = {{0, 2, 4}, {2, 1, 4}, {1, 3, 4}, {3, 0, 4},
                         {2, 0, 5}, {1, 2, 5}, {3, 1, 5}, {0, 3, 5}};
  for (int l = 0; l < levels; ++l) {
    std::vector<Face> nf;
    std::map<std::pair<Index, Index>, Index> mid;
    auto midpoint = [&](Index a, Index b) {
      auto key = std::minmax(a, b);
      auto it = mid.find({key.first, key.second});
      if (it != mid.end()) return it->second;
      v.push_back(((v[static_cast<size_t>(a)] + v[static_cast<size_t>(b)]) * 0.5).normalized());
      const Index id = static_cast<Index>(v.size() - 1);
      mid[{key.first, key.second}] = id;
      return id;
    };
    for (const Face& t : f) {
      const Index a = midpoint(t[0], t[1]), b = midpoint(t[1], t[2]), c = midpoint(t[2], t[0]);
      nf.push_back({t[0], a, c});
      nf.push_back({t[1], b, a});
      nf.push_back({t[2], c, b});
      nf.push_back({a, b, c});
    }
    f = std::move(nf);
  }
  auto topo = std::make_shared<Topology>();
  topo->num_vertices = static_cast<Index>(v.size());
  topo->faces = f;
  Object o;
  o.name = name;
  o.topology = topo;
  for (const Vec3& p : v) o.positions.push_back(center + p.normalized() * r * (1 + rng.uniform(-jitter, jitter)));
  return o;
}

/// A frame of `n` blobs in a box of side ~ `spread`; some overlap, some are far apart.
inline Frame make_random_frame(std::uint64_t seed, int n, double spread, int levels = 1) {
  Rng rng(seed);
  Frame frame;
  for (int i = 0; i < n; ++i) {
    const Vec3 c = rng.vec3(0, spread);
    frame.objects.push_back(make_blob(rng, c, rng.uniform(0.3, 1.0), levels, 0.3, "blob" + std::to_string(i)));
  }
  return frame;
}

/// A random triangle soup object (no shared vertices), `n` triangles of size ~ `size`.
inline Object make_soup(Rng& rng, const Vec3& center, double extent, double size, int n,
                        const std::string& name) {
  auto topo = std::make_shared<Topology>();
  Object o;
  o.name = name;
  for (int t = 0; t < n; ++t) {
    const Vec3 c = center + rng.vec3(-extent, extent);
    const Index base = static_cast<Index>(o.positions.size());
    for (int k = 0; k < 3; ++k)
      o.positions.push_back(c + rng.vec3(-size, size));
    topo->faces.push_back({base, base + 1, base + 2});
  }
  topo->num_vertices = static_cast<Index>(o.positions.size());
  o.topology = topo;
  return o;
}

/// Frame k+1 for `from`: every vertex moved by a per-object drift plus a random jitter of up
/// to `jitter`, so objects sweep into each other and fold onto themselves (CCD tests).
inline Frame moved(const Frame& from, std::uint64_t seed, double drift, double jitter) {
  Rng rng(seed);
  Frame to;
  to.index = from.index + 1;
  for (const Object& o : from.objects) {
    Object m = o;  // shares the topology pointer
    const Vec3 d = rng.vec3(-drift, drift);
    for (Vec3& p : m.positions) p += d + rng.vec3(-jitter, jitter);
    to.objects.push_back(std::move(m));
  }
  return to;
}

}  // namespace vproxq::test
