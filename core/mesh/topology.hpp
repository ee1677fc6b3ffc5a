#pragma once
// Mesh topology: what stays the same while positions change from frame to frame.
#include "core/types.hpp"

#include <memory>
#include <mutex>
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

/// Connectivity of one object: its vertex count and its faces, in file order. Objects hold it
/// as shared_ptr<const Topology>; frames whose faces are unchanged share the same one.
struct Topology {
  Index num_vertices = 0;
  std::vector<Face> faces;
  /// Filled by adjacency(); never part of equality.
  AdjacencyCache adjacency_cache;

  Index num_triangles() const { return static_cast<Index>(faces.size()); }
  bool operator==(const Topology& o) const {
    return num_vertices == o.num_vertices && faces == o.faces;
  }
  bool operator!=(const Topology& o) const { return !(*this == o); }
};

}  // namespace vproxq
