#pragma once
// Mesh topology: what stays the same while positions change from frame to frame.
#include "core/types.hpp"

#include <vector>

namespace vproxq {

/// Connectivity of one object: its vertex count and its faces, in file order.
struct Topology {
  Index num_vertices = 0;
  std::vector<Face> faces;

  Index num_triangles() const { return static_cast<Index>(faces.size()); }
  bool operator==(const Topology& o) const {
    return num_vertices == o.num_vertices && faces == o.faces;
  }
  bool operator!=(const Topology& o) const { return !(*this == o); }
};

}  // namespace vproxq
