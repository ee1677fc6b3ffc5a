#include "gl/ccd_voxel_backend.hpp"

#include <algorithm>
#include <cstdint>
#include <optional>
#include <string>
#include <utility>
#include <vector>

namespace vproxq::gl {
namespace {

ComputeProgram compile(const Context& context, const GlCcdVoxelOptions& options) {
  return ComputeProgram::from_embedded(context, "ccd_voxels",
                                       {{"LOCAL_SIZE", std::to_string(options.local_size)}});
}

/// A run of consecutive records with its own buffers.
struct Batch {
  std::size_t first = 0, count = 0;
  std::uint64_t room_first = 0, room = 0;  ///< key room: offset of the first record, size
};

}  // namespace

StorageBuffer& GlCcdVoxelBackend::reserve(std::optional<StorageBuffer>& buffer, std::size_t bytes,
                                          std::size_t cap, GLenum usage) {
  if (!buffer || buffer->size() < bytes) {
    buffer.reset();  // the old store goes before the new one is allocated
    buffer.emplace(context_, std::max(bytes, std::min(cap, bytes + bytes / 2)), usage);
  }
  return *buffer;
}

GlCcdVoxelBackend::GlCcdVoxelBackend(const Context& context, const GlCcdVoxelOptions& options)
    : context_(context), options_(options), program_(compile(context, options)) {}

CcdVoxelOutput GlCcdVoxelBackend::voxelize(const CcdVoxelInput& in) {
  CcdVoxelOutput out;
  const std::size_t n = in.records.size();
  out.keys.resize(static_cast<std::size_t>(in.out_offsets.back()));
  out.counts.assign(n, 0);
  if (in.cooccupancy) out.foreign.assign(n, 0);
  last_batch_count_ = 0;
  if (n == 0) return out;

  // Batches: key room, records (96 bytes each) and work groups within the limits.
  const ContextInfo& info = context_.info();
  const std::size_t local = program_.local_size()[0];
  std::size_t limit = static_cast<std::size_t>(info.max_ssbo_block_size);
  if (options_.max_batch_bytes > 0) limit = std::min(limit, options_.max_batch_bytes);
  const std::size_t max_records =
      std::min(limit / sizeof(CcdVoxelRecord), static_cast<std::size_t>(info.max_work_group_count[0]) * local);
  if (in.cooccupancy && std::size_t{in.key_count} * 4 > static_cast<std::size_t>(info.max_ssbo_block_size))
    throw GlError("GlCcdVoxelBackend: the co-occupancy table (" + std::to_string(in.key_count) +
                  " keys) exceeds GL_MAX_SHADER_STORAGE_BLOCK_SIZE; a coarser --grid (or --voronoi=cpu) needs less");
  std::vector<Batch> batches;
  for (std::size_t r = 0; r < n;) {
    Batch b;
    b.first = r;
    b.room_first = in.out_offsets[r];
    while (r < n && r - b.first < max_records && (in.out_offsets[r + 1] - b.room_first) * 4 <= limit) ++r;
    if (r == b.first)
      throw GlError("GlCcdVoxelBackend: record " + std::to_string(r) + " alone needs " +
                    std::to_string((in.out_offsets[r + 1] - in.out_offsets[r]) * 4) +
                    " bytes of keys, more than the buffer limit");
    b.count = r - b.first;
    b.room = in.out_offsets[r] - b.room_first;
    batches.push_back(std::move(b));
  }
  last_batch_count_ = batches.size();

  // The buffers stay from one step to the next and grow only (by half again, within the
  // limits): allocating them anew each step cost more than the upload itself on a hardware
  // driver (H100: up to 16 ms per step to clear a fresh 7 MB table).
  if (batch_buffers_.size() < batches.size()) batch_buffers_.resize(batches.size());
  const std::size_t table_bytes = in.cooccupancy ? std::size_t{in.key_count} * 4 : 4;
  const auto block = static_cast<std::size_t>(info.max_ssbo_block_size);
  out.upload_ms = finish_timed_ms(context_, [&] {
    reserve(table_, table_bytes, block, GL_DYNAMIC_DRAW).clear_to_zero(table_bytes);
    for (std::size_t k = 0; k < batches.size(); ++k) {
      const Batch& b = batches[k];
      BatchBuffers& buf = batch_buffers_[k];
      reserve(buf.records, b.count * sizeof(CcdVoxelRecord), limit, GL_STATIC_DRAW)
          .upload(in.records.data() + b.first, b.count * sizeof(CcdVoxelRecord));
      std::vector<std::uint32_t> offsets(b.count);
      for (std::size_t r = 0; r < b.count; ++r)
        offsets[r] = static_cast<std::uint32_t>(in.out_offsets[b.first + r] - b.room_first);
      reserve(buf.offsets, 4 * b.count, limit, GL_STATIC_DRAW).upload(offsets.data(), 4 * b.count);
      reserve(buf.objects, 4 * b.count, limit, GL_STATIC_DRAW)
          .upload(in.record_object.data() + b.first, 4 * b.count);
      reserve(buf.keys, std::max<std::size_t>(4, static_cast<std::size_t>(b.room) * 4), limit, GL_STREAM_READ);
      reserve(buf.counts, 4 * b.count, limit, GL_STREAM_READ);
      reserve(buf.foreign, 4 * b.count, limit, GL_STREAM_READ);
    }
  });

  out.compute_ms = finish_timed_ms(context_, [&] {
    program_.set_uint("dims_x", static_cast<GLuint>(in.dims[0]));
    program_.set_uint("dims_y", static_cast<GLuint>(in.dims[1]));
    program_.set_uint("cooccupancy", in.cooccupancy ? 1u : 0u);
    table_->bind(5);
    // Pass 1 reads the table that pass 0 of every batch has finished writing.
    for (GLuint pass = 0; pass < (in.cooccupancy ? 2u : 1u); ++pass) {
      program_.set_uint("pass", pass);
      for (std::size_t k = 0; k < batches.size(); ++k) {
        const Batch& b = batches[k];
        const BatchBuffers& buf = batch_buffers_[k];
        buf.records->bind(0);
        buf.offsets->bind(1);
        buf.objects->bind(2);
        buf.keys->bind(3);
        buf.counts->bind(4);
        buf.foreign->bind(6);
        program_.set_uint("record_count", static_cast<GLuint>(b.count));
        dispatch(context_, program_, group_count(b.count, static_cast<GLuint>(local)));
      }
      memory_barrier(context_);
    }
  });

  out.readback_ms = finish_timed_ms(context_, [&] {
    for (std::size_t k = 0; k < batches.size(); ++k) {
      const Batch& b = batches[k];
      const BatchBuffers& buf = batch_buffers_[k];
      if (b.room > 0) buf.keys->download(out.keys.data() + b.room_first, static_cast<std::size_t>(b.room) * 4);
      buf.counts->download(out.counts.data() + b.first, 4 * b.count);
      if (in.cooccupancy) buf.foreign->download(out.foreign.data() + b.first, 4 * b.count);
    }
  });
  // A record whose box the shader did not finish (a driver's loop cap, see ccd_voxels.comp):
  // the keys and the table are incomplete, so the whole input is done on the CPU, whose
  // integer work gives the same output.
  const bool incomplete =
      std::any_of(out.counts.begin(), out.counts.end(), [](std::uint32_t c) { return c == 0xFFFFFFFFu; }) ||
      std::any_of(out.foreign.begin(), out.foreign.end(), [](std::uint32_t f) { return f == 2; });
  last_fell_back_ = incomplete;
  if (incomplete) {
    CcdVoxelOutput cpu = make_cpu_ccd_voxel_backend(options_.cpu_threads)->voxelize(in);
    cpu.upload_ms += out.upload_ms;
    cpu.compute_ms += out.compute_ms;
    cpu.readback_ms += out.readback_ms;
    return cpu;
  }
  return out;
}

}  // namespace vproxq::gl
