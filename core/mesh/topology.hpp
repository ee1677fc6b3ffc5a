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
///
/// A mesh the file gives no name of its own (a PLY or OFF file, an OBJ without groups, an
/// unnamed OBJ group, an unnamed assimp mesh) is named after the file, and the file name
/// changes from frame to frame: when it is the file's only unnamed mesh, it is identified as
/// that (`file_named`) instead of by its name. (Of several unnamed meshes in one file,
/// none is: pairing them by position would read a mesh that vanished and its neighbour as
/// one moving mesh.) Meshes of the scene's static files are also told apart by the file
/// (`static_file`).
struct ComponentOrigin {
  std::string mesh;         ///< the mesh's name (for messages; identifies it unless file_named)
  bool file_named = false;  ///< the only mesh its file does not name (named after the file)
  int static_file = -1;   ///< for static geometry, the position of its file in "static"
  std::vector<Index> vertices;
  bool empty() const { return vertices.empty(); }
  /// Whether both come from the same mesh: the same static file (or none), then both their
  /// file's only unnamed mesh, or else the same name.
  bool same_mesh(const ComponentOrigin& o) const {
    if (static_file != o.static_file || file_named != o.file_named) return false;
    return file_named || mesh == o.mesh;
  }
  /// Orders origins by mesh (as same_mesh() identifies it), then vertices.
  bool operator<(const ComponentOrigin& o) const {
    if (static_file != o.static_file) return static_file < o.static_file;
    if (file_named != o.file_named) return file_named < o.file_named;
    if (!file_named && mesh != o.mesh) return mesh < o.mesh;
    return vertices < o.vertices;
  }
  bool operator==(const ComponentOrigin& o) const { return vertices == o.vertices && same_mesh(o); }
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
