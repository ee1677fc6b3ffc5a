#pragma once
// Scene input: scene.json (or a bare mesh file) -> frames, loaded one at a time on request.
#include "core/scene.hpp"

#include <array>
#include <filesystem>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

namespace vproxq {

/// The queries, in canonical order (DESIGN.md, table of queries): what --queries and scene.json
/// "queries" may list.
inline constexpr std::array<std::string_view, 3> kQueryNames = {"distance", "ccd", "pd"};

/// kQueryNames joined by ", ", for messages and help.
std::string query_names_list();

/// How a frame file splits into objects (scene.json "objects").
enum class ObjectSplit { Meshes, Components };

/// Largest Voronoi grid resolution (cells along the longest axis) that the scene's "grid" and
/// --grid accept: Stage II's memory grows with the number of marked voxels, which grows with
/// the square of the resolution (the cube for the CCD grid's bound), and 4096 already needs
/// gigabytes on small scenes.
inline constexpr int kMaxGridResolution = 4096;

/// Which frame files SceneSource::open() checks: all of them, or none (the caller checks the
/// ones it will read with require_frames(), so that a run over the first frames of a sequence
/// still being written does not fail on the frames not written yet).
enum class FrameFileCheck { All, Deferred };

/// A parsed scene. Frames are read from disk only in load_frame(), so memory does not grow
/// with the number of frames. Static geometry is read once and shared by every frame.
class SceneSource {
 public:
  /// Opens a scene.json, or a bare mesh file (.obj, .ply, or anything assimp reads) as a
  /// one-frame scene. Checks the whole description, reads the static files, and checks that
  /// every frame file exists (`check` All) or none (Deferred: see require_frames()).
  /// Throws InputError naming the file and, for scene.json, the key and why it is wrong.
  static SceneSource open(const std::filesystem::path& path, FrameFileCheck check = FrameFileCheck::All);

  /// Checks that the frame files of positions [first, last) exist and are regular files
  /// (last is capped at frame_count()); throws InputError naming scene.json, the key that
  /// lists the file, the frame and the file, as open() does with FrameFileCheck::All.
  void require_frames(std::size_t first, std::size_t last) const;

  const std::string& name() const;
  const std::filesystem::path& path() const;
  std::size_t frame_count() const;
  /// scene.json "queries" (empty when absent) and "grid" (nullopt when absent; at most
  /// kMaxGridResolution).
  const std::vector<std::string>& queries() const;
  std::optional<int> grid() const;
  /// scene.json "self" (nullopt when absent): whether "distance" runs its intra-object part.
  std::optional<bool> self() const;
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
