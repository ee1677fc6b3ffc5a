#pragma once
// What the two Stage II GL backends (voronoi_backend.cpp: dvd2_gather.comp, and
// self_voronoi_backend.cpp: dvd_self_gather.comp appended to it) share: input checks, the
// batching of samples into dispatches, the triangle and bin buffers (bindings 0-3), the sample
// buffer (binding 4) and the grid uniforms.
#include "core/voronoi/discrete_voronoi.hpp"
#include "gl/compute.hpp"

#include <cstdint>
#include <string>
#include <utility>
#include <vector>

namespace vproxq::gl {

/// Largest |coordinate| of the input: triangle corners and the grid box (sample points).
double dvd_input_extent(const DvdInput& in);

/// Throws std::invalid_argument (prefixed with `who`) when the shaders cannot address the
/// grid exactly (2^23 voxels per side) or the float and double triangles differ in size.
void check_dvd_addressable(const DvdInput& in, const std::string& who);

/// Splits `count` samples into dispatches of at most GL_MAX_COMPUTE_WORK_GROUP_COUNT[0] groups
/// (or `max_groups` when > 0) whose 16-byte-per-sample buffers fit
/// GL_MAX_SHADER_STORAGE_BLOCK_SIZE: (first, count) pairs.
std::vector<std::pair<std::size_t, std::size_t>> plan_batches(const Context& context,
                                                              const ComputeProgram& program,
                                                              std::size_t count,
                                                              unsigned max_groups);

/// Bindings 0-3 of dvd2_gather.comp: triangles (float), per-triangle info (site and first
/// bin), bin offsets, bin triangles.
struct DvdSharedBuffers {
  StorageBuffer triangles, triangle_info, bin_offsets, bin_tris;

  static DvdSharedBuffers upload(const Context& context, const DvdInput& in);
  void bind() const;
};

/// `in` with only the sample voxels `picks` (indices into in.voxels, in that order): their
/// bands and exclusions, the same grid, triangles and bins. For computing the samples a
/// shader could not finish with the CPU twin.
DvdInput with_samples(const DvdInput& in, const std::vector<std::size_t>& picks);

/// Binding 4 of a batch: per sample, its voxel coordinates (x, y, z) and the float bits of its
/// band.
std::vector<std::uint32_t> pack_samples(const DvdInput& in, std::size_t first, std::size_t count);

/// The grid and bin uniforms, and the prefilter margin: twice `error_bound`, rounded up to
/// float (the margin must not shrink; see dvd2_gather.comp).
void set_dvd_uniforms(ComputeProgram& program, const DvdInput& in, double error_bound);

/// Runs one dispatch per batch (each batch has `count` samples; bind_batch(batch) binds its
/// own buffers; the shared ones are bound already) and waits for the shader writes: the
/// compute time in ms. Adds the dispatches to `dispatch_count`.
template <typename Batches, typename Bind>
double dispatch_batches(const Context& context, ComputeProgram& program, const Batches& batches,
                        const Bind& bind_batch, std::size_t& dispatch_count) {
  const auto local_size = static_cast<GLuint>(program.local_size()[0]);
  return finish_timed_ms(context, [&] {
    for (const auto& batch : batches) {
      bind_batch(batch);
      program.set_uint("sample_count", static_cast<GLuint>(batch.count));
      dispatch(context, program, group_count(batch.count, local_size));
      ++dispatch_count;
    }
    memory_barrier(context);
  });
}

}  // namespace vproxq::gl
