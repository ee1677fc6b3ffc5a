#include "io/mesh_reader.hpp"

#include "io/assimp_reader.hpp"
#include "io/mesh_reader_detail.hpp"
#include "io/obj_reader.hpp"
#include "io/off_reader.hpp"
#include "io/ply_reader.hpp"
#include "io/read_util.hpp"

#include <numeric>

namespace vproxq {

namespace fs = std::filesystem;

std::vector<MeshGroup> read_mesh_file(const fs::path& file) {
  const std::string ext = io_detail::lower_extension(file);
  if (ext == ".obj") return io_detail::read_obj(file, io_detail::ObjGroups::Split);
  if (ext == ".ply") {
    std::vector<MeshGroup> groups;
    groups.push_back(io_detail::read_ply(file));
    return groups;
  }
  if (ext == ".off") {
    std::vector<MeshGroup> groups;
    groups.push_back(io_detail::read_off(file));
    return groups;
  }
  return io_detail::read_with_assimp(file);
}

namespace io_detail {

MeshGroup read_mesh_file_merged(const fs::path& file) {
  const std::string ext = lower_extension(file);
  if (ext == ".obj") {
    std::vector<MeshGroup> one = read_obj(file, ObjGroups::Merge);
    return std::move(one.front());
  }
  if (ext == ".ply") return read_ply(file);
  if (ext == ".off") return read_off(file);
  std::vector<MeshGroup> groups = read_with_assimp(file);
  MeshGroup merged;
  merged.name = file.stem().string();
  for (const MeshGroup& g : groups) {
    const auto offset = static_cast<Index>(merged.positions.size());
    merged.positions.insert(merged.positions.end(), g.positions.begin(), g.positions.end());
    for (const Face& f : g.faces)
      merged.faces.push_back({f[0] + offset, f[1] + offset, f[2] + offset});
  }
  return merged;
}

}  // namespace io_detail

namespace {

/// Union-find over vertex indices, with path halving and union by size.
class DisjointSets {
 public:
  explicit DisjointSets(std::size_t n) : parent_(n), size_(n, 1) {
    std::iota(parent_.begin(), parent_.end(), Index{0});
  }
  Index find(Index v) {
    auto i = static_cast<std::size_t>(v);
    while (parent_[i] != static_cast<Index>(i)) {
      parent_[i] = parent_[static_cast<std::size_t>(parent_[i])];
      i = static_cast<std::size_t>(parent_[i]);
    }
    return static_cast<Index>(i);
  }
  void unite(Index a, Index b) {
    auto ra = static_cast<std::size_t>(find(a));
    auto rb = static_cast<std::size_t>(find(b));
    if (ra == rb) return;
    if (size_[ra] < size_[rb]) std::swap(ra, rb);
    parent_[rb] = static_cast<Index>(ra);
    size_[ra] += size_[rb];
  }

 private:
  std::vector<Index> parent_;
  std::vector<std::size_t> size_;
};

}  // namespace

// Components are named "<group name>#<k>", k = 0, 1, ... in order of their first face.
// Vertices that no face uses belong to no component and are dropped.
std::vector<MeshGroup> split_components(const MeshGroup& group) {
  const std::size_t nv = group.positions.size();
  DisjointSets sets(nv);
  for (const Face& f : group.faces) {
    sets.unite(f[0], f[1]);
    sets.unite(f[0], f[2]);
  }
  // Component of each root, numbered by first face.
  std::vector<Index> component_of_root(nv, kNoIndex);
  std::vector<Index> face_component(group.faces.size());
  Index num_components = 0;
  for (std::size_t i = 0; i < group.faces.size(); ++i) {
    const auto root = static_cast<std::size_t>(sets.find(group.faces[i][0]));
    if (component_of_root[root] == kNoIndex) component_of_root[root] = num_components++;
    face_component[i] = component_of_root[root];
  }
  std::vector<MeshGroup> parts(static_cast<std::size_t>(num_components));
  for (std::size_t c = 0; c < parts.size(); ++c) {
    parts[c].name = group.name + "#" + std::to_string(c);
    parts[c].origin.mesh = group.name;
    parts[c].origin.file_named = group.file_named;
  }
  // Vertices in global order; a vertex belongs to its root's component if that has faces.
  std::vector<Index> local(nv, kNoIndex);
  for (std::size_t v = 0; v < nv; ++v) {
    const Index c = component_of_root[static_cast<std::size_t>(sets.find(static_cast<Index>(v)))];
    if (c == kNoIndex) continue;  // isolated vertex
    MeshGroup& part = parts[static_cast<std::size_t>(c)];
    local[v] = static_cast<Index>(part.positions.size());
    part.positions.push_back(group.positions[v]);
    part.origin.vertices.push_back(static_cast<Index>(v));
  }
  for (std::size_t i = 0; i < group.faces.size(); ++i) {
    const Face& f = group.faces[i];
    parts[static_cast<std::size_t>(face_component[i])].faces.push_back(
        {local[static_cast<std::size_t>(f[0])], local[static_cast<std::size_t>(f[1])],
         local[static_cast<std::size_t>(f[2])]});
  }
  return parts;
}

}  // namespace vproxq
