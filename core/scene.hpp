#pragma once
// One frame of a scene: objects, each a topology plus this frame's vertex positions.
#include "core/mesh/topology.hpp"
#include "core/types.hpp"

#include <memory>
#include <string>
#include <vector>

namespace vproxq {

struct Object {
  std::string name;
  std::shared_ptr<const Topology> topology;
  std::vector<Vec3> positions;  ///< size() == topology->num_vertices
  bool is_static = false;       ///< from the scene's "static" list

  Index num_vertices() const { return topology->num_vertices; }
  Index num_triangles() const { return topology->num_triangles(); }
  Triangle triangle(Index t) const {
    const Face& f = topology->faces[static_cast<size_t>(t)];
    return {positions[static_cast<size_t>(f[0])], positions[static_cast<size_t>(f[1])],
            positions[static_cast<size_t>(f[2])]};
  }
};

struct Frame {
  int index = 0;                   ///< position in the scene's sequence (0-based)
  std::vector<std::string> files;  ///< files this frame was read from (for messages)
  std::vector<Object> objects;
};

}  // namespace vproxq
