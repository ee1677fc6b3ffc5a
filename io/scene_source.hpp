#pragma once
// Scene input: scene.json (or a bare mesh file) -> frames, loaded one at a time on request.
#include "core/scene.hpp"

#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <vector>

namespace vproxq {

/// How a frame file splits into objects (scene.json "objects").
enum class ObjectSplit { Meshes, Components };

/// A parsed scene. Frames are read from disk only in load_frame(), so memory does not grow
/// with the number of frames. Static geometry is read once and shared by every frame.
class SceneSource {
 public:
  /// Opens a scene.json, or a bare mesh file (.obj, .ply, or anything assimp reads) as a
  /// one-frame scene. Checks the whole description and that every frame file exists.
  /// Throws InputError naming the file and, for scene.json, the key and why it is wrong.
  static SceneSource open(const std::filesystem::path& path);

  const std::string& name() const;
  const std::filesystem::path& path() const;
  std::size_t frame_count() const;
  /// scene.json "queries" (empty when absent) and "grid" (nullopt when absent).
  const std::vector<std::string>& queries() const;
  std::optional<int> grid() const;
  ObjectSplit split() const;

  /// Reads frame k (0-based position in the sequence): all objects, then the static ones.
  /// Throws InputError naming the file: unreadable or malformed mesh, out-of-range face index,
  /// NaN or Inf coordinate, empty frame (no triangles at all), or, with ObjectSplit::Meshes or
  /// per-object sequences, an object count that differs from the first frame loaded.
  Frame load_frame(std::size_t k) const;

  SceneSource(SceneSource&&) noexcept;
  SceneSource& operator=(SceneSource&&) noexcept;
  ~SceneSource();

 private:
  struct Impl;
  explicit SceneSource(std::unique_ptr<Impl> impl);
  std::unique_ptr<Impl> impl_;
};

}  // namespace vproxq
