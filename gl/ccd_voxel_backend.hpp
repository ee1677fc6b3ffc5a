#pragma once
// CCD Stage II on the GPU: the CcdVoxelBackend of core/voronoi/ccd_stage2.hpp as an OpenGL 4.3
// compute shader (shaders/ccd_voxels.comp), one invocation per (triangle, time slot) record.
// Pass 0 lists each record's voxels and marks the dense co-occupancy table with atomics; pass
// 1 flags the records with a key of two objects. Integer work only: the output equals the CPU
// backend's bit for bit (tests/gl/test_ccd_voxels_gl.cpp).
#include "core/voronoi/ccd_stage2.hpp"
#include "gl/compute.hpp"

#include <cstddef>
#include <optional>
#include <string>
#include <vector>

namespace vproxq::gl {

struct GlCcdVoxelOptions {
  GLuint local_size = 64;  ///< work group size (LOCAL_SIZE define of the shader)
  /// Largest key buffer of one batch in bytes; 0: GL_MAX_SHADER_STORAGE_BLOCK_SIZE. Records
  /// are processed in batches whose key room fits (tests use small values to exercise it).
  std::size_t max_batch_bytes = 0;
  /// Threads of the CPU twin that redoes a step the shader could not finish; 0: all cores.
  int cpu_threads = 0;
};

/// Lifetime and threading as GlVoronoiBackend: `context` must outlive the backend, stay in
/// place and be current on the thread that uses it.
class GlCcdVoxelBackend final : public CcdVoxelBackend {
 public:
  explicit GlCcdVoxelBackend(const Context& context, const GlCcdVoxelOptions& options = {});
  std::string name() const override { return "gpu"; }
  /// Throws GlError when a record's room alone exceeds the buffer limit or a GL call fails.
  CcdVoxelOutput voxelize(const CcdVoxelInput& in) override;
  std::size_t last_batch_count() const { return last_batch_count_; }
  /// Whether the last voxelize() was redone on the CPU because the shader could not finish a
  /// record's box (a driver's loop cap: ccd_voxels.comp).
  bool last_fell_back() const { return last_fell_back_; }

 private:
  /// One batch's buffers, kept for the next call.
  struct BatchBuffers {
    std::optional<StorageBuffer> records, offsets, objects, keys, counts, foreign;
  };
  /// `buffer` with at least `bytes` bytes: kept if large enough, else allocated anew with
  /// half again as many bytes, at most `cap` (but never fewer than `bytes`).
  StorageBuffer& reserve(std::optional<StorageBuffer>& buffer, std::size_t bytes, std::size_t cap,
                         GLenum usage);

  const Context& context_;
  GlCcdVoxelOptions options_;
  ComputeProgram program_;
  std::optional<StorageBuffer> table_;  ///< the co-occupancy table (its first key_count words)
  std::vector<BatchBuffers> batch_buffers_;
  std::size_t last_batch_count_ = 0;
  bool last_fell_back_ = false;
};

}  // namespace vproxq::gl
