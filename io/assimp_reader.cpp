#include "io/assimp_reader.hpp"

#include "io/read_util.hpp"

#include <assimp/postprocess.h>
#include <assimp/config.h>
#include <assimp/scene.h>
#include <Eigen/Geometry>
#include <assimp/Importer.hpp>

#include <array>
#include <cctype>
#include <map>
#include <string>
#include <vector>

namespace vproxq::io_detail {

namespace fs = std::filesystem;

namespace {

using Affine = Eigen::Transform<double, 3, Eigen::Affine>;

Affine to_eigen(const aiMatrix4x4& m) {
  Eigen::Matrix4d e;
  e << m.a1, m.a2, m.a3, m.a4, m.b1, m.b2, m.b3, m.b4, m.c1, m.c2, m.c3, m.c4, m.d1, m.d2, m.d3,
      m.d4;
  return Affine(e);
}

struct MeshRef {
  unsigned mesh;
  Affine transform;
  std::string node_name;
  bool is_root;
};

void collect(const aiNode* node, const Affine& parent, bool is_root, std::vector<MeshRef>& out) {
  const Affine t = parent * to_eigen(node->mTransformation);
  for (unsigned i = 0; i < node->mNumMeshes; ++i) {
    out.push_back({node->mMeshes[i], t, node->mName.C_Str(), is_root});
  }
  for (unsigned c = 0; c < node->mNumChildren; ++c) collect(node->mChildren[c], t, false, out);
}

/// Corners at bitwise-equal positions (after the node transform) become one vertex, numbered
/// in the order of first use; -0 and +0 are equal. Positions and faces are rewritten in place.
/// For STL only, which stores every facet with its own three corners (so a closed mesh would
/// be a soup); formats with shared vertices keep assimp's.
void weld(MeshGroup& g) {
  std::map<std::array<double, 3>, Index> first;
  std::vector<Index> to(g.positions.size());
  std::vector<Vec3> kept;
  for (std::size_t v = 0; v < g.positions.size(); ++v) {
    const Vec3& p = g.positions[v];
    const auto [it, added] = first.try_emplace({p.x(), p.y(), p.z()}, static_cast<Index>(kept.size()));
    if (added) kept.push_back(p);
    to[v] = it->second;
  }
  for (Face& f : g.faces)
    for (Index& v : f) v = to[static_cast<std::size_t>(v)];
  g.positions = std::move(kept);
}

MeshGroup convert(const fs::path& file, const aiMesh& mesh, const MeshRef& ref, bool welded) {
  const std::string mesh_name = mesh.mName.C_Str();
  const std::string label = mesh_name.empty() ? std::to_string(ref.mesh) : "'" + mesh_name + "'";
  MeshGroup g;
  g.name = !mesh_name.empty() ? mesh_name : (ref.is_root ? std::string() : ref.node_name);
  g.positions.reserve(mesh.mNumVertices);
  for (unsigned v = 0; v < mesh.mNumVertices; ++v) {
    const aiVector3D& a = mesh.mVertices[v];
    const Vec3 p = ref.transform * Vec3(a.x, a.y, a.z);
    if (const std::string problem = coordinate_problem(p); !problem.empty())
      throw_input_error(file, "mesh " + label + ": vertex " + std::to_string(v) + " (0-based) " + problem);
    g.positions.push_back(p);
  }
  g.faces.reserve(mesh.mNumFaces);
  for (unsigned f = 0; f < mesh.mNumFaces; ++f) {
    const aiFace& face = mesh.mFaces[f];
    if (face.mNumIndices < 3) {
      throw_input_error(file, "mesh " + label + ": face " + std::to_string(f) + " has " +
                                  std::to_string(face.mNumIndices) +
                                  " vertices (a face needs at least 3; points and lines are "
                                  "not supported)");
    }
    for (unsigned i = 0; i < face.mNumIndices; ++i) {
      if (face.mIndices[i] >= mesh.mNumVertices) {
        throw_input_error(file, "mesh " + label + ": face " + std::to_string(f) +
                                    ": vertex index " + std::to_string(face.mIndices[i]) +
                                    " out of range (mesh has " + std::to_string(mesh.mNumVertices) +
                                    " vertices)");
      }
    }
    // aiProcess_Triangulate leaves only triangles; fan anything else to be safe.
    for (unsigned i = 1; i + 1 < face.mNumIndices; ++i) {
      g.faces.push_back({static_cast<Index>(face.mIndices[0]), static_cast<Index>(face.mIndices[i]),
                         static_cast<Index>(face.mIndices[i + 1])});
    }
  }
  if (welded) weld(g);
  return g;
}

}  // namespace

std::vector<MeshGroup> read_with_assimp(const fs::path& file) {
  require_regular_file(file);
  Assimp::Importer importer;
  // Coordinates as written: no rotation of Z_UP / X_UP Collada files to assimp's Y up.
  importer.SetPropertyBool(AI_CONFIG_IMPORT_COLLADA_IGNORE_UP_DIRECTION, true);
  // Triangulate only: JoinIdenticalVertices and the other position-dependent steps would
  // change topology from frame to frame. STL is welded by weld() instead: assimp's
  // JoinIdenticalVertices also compares normals, so it keeps the corners of flat-shaded
  // facets apart.
  const aiScene* scene = importer.ReadFile(file.string(), aiProcess_Triangulate);
  if (scene == nullptr) {
    throw_input_error(file, std::string("assimp: ") + importer.GetErrorString());
  }
  if ((scene->mFlags & AI_SCENE_FLAGS_INCOMPLETE) != 0) {
    throw_input_error(file, "assimp: the scene is incomplete (no usable meshes)");
  }

  std::string ext = file.extension().string();
  for (char& c : ext) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
  const bool stl = ext == ".stl";

  std::vector<MeshRef> refs;
  if (scene->mRootNode != nullptr) {
    collect(scene->mRootNode, Affine::Identity(), true, refs);
  } else {
    for (unsigned m = 0; m < scene->mNumMeshes; ++m) {
      refs.push_back({m, Affine::Identity(), std::string(), true});
    }
  }

  std::vector<MeshGroup> groups;
  for (const MeshRef& ref : refs) {
    if (ref.mesh >= scene->mNumMeshes) {
      throw_input_error(file, "assimp: a node refers to mesh " + std::to_string(ref.mesh) +
                                  ", the file has " + std::to_string(scene->mNumMeshes));
    }
    const aiMesh& mesh = *scene->mMeshes[ref.mesh];
    if (mesh.mNumFaces == 0) continue;
    groups.push_back(convert(file, mesh, ref, stl));
  }
  const std::string stem = file.stem().string();
  // The only unnamed mesh of a file is identified across frames as such (ComponentOrigin);
  // of several, none is.
  const auto unnamed = std::count_if(groups.begin(), groups.end(), [](const MeshGroup& g) { return g.name.empty(); });
  for (std::size_t k = 0; k < groups.size(); ++k) {
    if (groups[k].name.empty()) {
      groups[k].name = groups.size() == 1 ? stem : stem + "_" + std::to_string(k);
      groups[k].file_named = unnamed == 1;
    }
  }
  return groups;
}

}  // namespace vproxq::io_detail
