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
  std::optional<StorageBuffer> records, offsets, objects, keys, counts, foreign;
};

}  // namespace

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

  std::optional<StorageBuffer> table;
  out.upload_ms = finish_timed_ms(context_, [&] {
    table.emplace(context_, in.cooccupancy ? std::size_t{in.key_count} * 4 : 4);
    table->clear_to_zero();
    for (Batch& b : batches) {
      const std::vector<CcdVoxelRecord> recs(in.records.begin() + static_cast<std::ptrdiff_t>(b.first),
                                             in.records.begin() + static_cast<std::ptrdiff_t>(b.first + b.count));
      b.records.emplace(StorageBuffer::from_vector(context_, recs));
      std::vector<std::uint32_t> offsets(b.count);
      for (std::size_t k = 0; k < b.count; ++k)
        offsets[k] = static_cast<std::uint32_t>(in.out_offsets[b.first + k] - b.room_first);
      b.offsets.emplace(StorageBuffer::from_vector(context_, offsets));
      const std::vector<std::int32_t> objects(in.record_object.begin() + static_cast<std::ptrdiff_t>(b.first),
                                              in.record_object.begin() + static_cast<std::ptrdiff_t>(b.first + b.count));
      b.objects.emplace(StorageBuffer::from_vector(context_, objects));
      b.keys.emplace(context_, std::max<std::size_t>(4, static_cast<std::size_t>(b.room) * 4), GL_STREAM_READ);
      b.counts.emplace(context_, 4 * b.count, GL_STREAM_READ);
      b.foreign.emplace(context_, 4 * b.count, GL_STREAM_READ);
    }
  });

  out.compute_ms = finish_timed_ms(context_, [&] {
    program_.set_uint("dims_x", static_cast<GLuint>(in.dims[0]));
    program_.set_uint("dims_y", static_cast<GLuint>(in.dims[1]));
    program_.set_uint("cooccupancy", in.cooccupancy ? 1u : 0u);
    table->bind(5);
    // Pass 1 reads the table that pass 0 of every batch has finished writing.
    for (GLuint pass = 0; pass < (in.cooccupancy ? 2u : 1u); ++pass) {
      program_.set_uint("pass", pass);
      for (const Batch& b : batches) {
        b.records->bind(0);
        b.offsets->bind(1);
        b.objects->bind(2);
        b.keys->bind(3);
        b.counts->bind(4);
        b.foreign->bind(6);
        program_.set_uint("record_count", static_cast<GLuint>(b.count));
        dispatch(context_, program_, group_count(b.count, static_cast<GLuint>(local)));
      }
      memory_barrier(context_);
    }
  });

  out.readback_ms = finish_timed_ms(context_, [&] {
    for (const Batch& b : batches) {
      if (b.room > 0) b.keys->download(out.keys.data() + b.room_first, static_cast<std::size_t>(b.room) * 4);
      b.counts->download(out.counts.data() + b.first, 4 * b.count);
      if (in.cooccupancy) b.foreign->download(out.foreign.data() + b.first, 4 * b.count);
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
