#pragma once
// Mesh topology: what stays the same while positions change from frame to frame.
#include "core/types.hpp"

#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace vproxq {

class Adjacency;

/// Holds derived connectivity next to the faces it was computed from. A copy starts empty
/// (it is recomputed on demand), so Topology stays an ordinary copyable value.
class AdjacencyCache {
 public:
  AdjacencyCache() = default;
  AdjacencyCache(const AdjacencyCache&) {}
  AdjacencyCache& operator=(const AdjacencyCache&) {
    std::lock_guard<std::mutex> lock(mutex_);
    value_.reset();
    return *this;
  }

 private:
  friend const Adjacency& adjacency(const struct Topology&);
  mutable std::mutex mutex_;
  mutable std::shared_ptr<const Adjacency> value_;
};

/// Where a connected component of a mesh ("objects": "components") came from: the mesh's name
/// and, per vertex of the component, its index among the mesh's vertices. Empty for an object
/// that is a whole mesh. CCD pairs a component with the component of the next frame that holds
/// the same vertices of the same mesh (its name "<mesh>#k" only numbers the pieces).
struct ComponentOrigin {
  std::string mesh;
  std::vector<Index> vertices;
  bool empty() const { return vertices.empty(); }
  bool operator==(const ComponentOrigin& o) const { return vertices == o.vertices && mesh == o.mesh; }
  bool operator!=(const ComponentOrigin& o) const { return !(*this == o); }
};

/// Connectivity of one object: its vertex count and its faces, in file order. Objects hold it
/// as shared_ptr<const Topology>; frames whose faces (and origin) are unchanged share the same one.
struct Topology {
  Index num_vertices = 0;
  std::vector<Face> faces;
  ComponentOrigin origin;
  /// Filled by adjacency(); never part of equality.
  AdjacencyCache adjacency_cache;

  Index num_triangles() const { return static_cast<Index>(faces.size()); }
  bool operator==(const Topology& o) const {
    return num_vertices == o.num_vertices && faces == o.faces && origin == o.origin;
  }
  bool operator!=(const Topology& o) const { return !(*this == o); }
};

}  // namespace vproxq
