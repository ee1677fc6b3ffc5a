#include "gl/self_voronoi_backend.hpp"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <utility>
#include <vector>

#include "core/voronoi/bins.hpp"
#include "gl/shader_source.hpp"

namespace vproxq::gl {
namespace {

/// dvd2_gather.comp with its main() renamed, then dvd_self_gather.comp: the self shader
/// shares the buffers, uniforms, distance function and error analysis of the inter-object one.
ComputeProgram compile(const Context& context, const GlVoronoiOptions& options) {
  std::string body = "#define main dvd2_gather_main\n";
  body += shader_source("dvd2_gather");
  body += "\n#undef main\n#line 1 1\n";  // compiler logs: string 1 is dvd_self_gather.comp
  body += shader_source("dvd_self_gather");
  return ComputeProgram(context, "dvd_self_gather",
                        compose_shader_source(body, {{"LOCAL_SIZE", std::to_string(options.local_size)}}));
}

/// Largest |coordinate| of the input: triangle corners and the grid box (sample points).
double input_extent(const DvdInput& in) {
  double extent = in.grid.cell *
                  static_cast<double>(*std::max_element(in.grid.dims.begin(), in.grid.dims.end()));
  for (const double c : in.tri_xyz_d) extent = std::max(extent, std::abs(c));
  return extent;
}

struct Batch {
  std::size_t first = 0;
  std::size_t count = 0;
  std::optional<StorageBuffer> samples, sample_triangles, results;
};

}  // namespace

GlSelfVoronoiBackend::GlSelfVoronoiBackend(const Context& context, const GlVoronoiOptions& options)
    : context_(context), options_(options), program_(compile(context, options)) {}

std::string GlSelfVoronoiBackend::device() const { return context_.renderer(); }

double GlSelfVoronoiBackend::distance_error_bound(double extent) const {
  return GlVoronoiBackend::float32_error_bound(extent);
}

SelfDvdOutput GlSelfVoronoiBackend::compute(const SelfDvdInput& self) {
  validate_self_dvd_input(self);
  const DvdInput& in = self.dvd;
  if (in.grid.voxel_count() > std::int64_t{std::numeric_limits<std::uint32_t>::max()} ||
      *std::max_element(in.grid.dims.begin(), in.grid.dims.end()) >= (1 << 23)) {
    throw std::invalid_argument("GlSelfVoronoiBackend: the grid is too large for the shader");
  }
  if (in.tri_xyz.size() != in.tri_xyz_d.size())
    throw std::invalid_argument("GlSelfVoronoiBackend: tri_xyz and tri_xyz_d differ in size");
  SelfDvdOutput out;
  last_dispatch_count_ = 0;
  const std::size_t sample_count = in.voxels.size();
  const std::size_t tri_count = in.tri_site.size();
  out.dist.resize(sample_count);
  last_nearest_.assign(sample_count, kNoIndex);
  if (sample_count == 0) return out;

  // Batches as in GlVoronoiBackend: within the work group count and the SSBO block size.
  const ContextInfo& info = context_.info();
  const std::size_t local_size = program_.local_size()[0];
  std::size_t groups = static_cast<std::size_t>(info.max_work_group_count[0]);
  if (options_.max_groups_per_dispatch > 0)
    groups = std::min<std::size_t>(groups, options_.max_groups_per_dispatch);
  std::size_t batch_size = local_size * groups;
  const auto block_limit = static_cast<std::size_t>(info.max_ssbo_block_size) / 16;
  if (block_limit > 0) batch_size = std::min(batch_size, block_limit / local_size * local_size);
  batch_size = std::max(batch_size, local_size);
  std::vector<Batch> batches;
  for (std::size_t first = 0; first < sample_count; first += batch_size) {
    Batch batch;
    batch.first = first;
    batch.count = std::min(batch_size, sample_count - first);
    batches.push_back(std::move(batch));
  }

  std::optional<StorageBuffer> triangles, triangle_info, bin_offsets, bin_tris, vertices;
  out.upload_ms = finish_timed_ms(context_, [&] {
    std::vector<std::int32_t> tri_info(4 * tri_count), tri_vertices(4 * tri_count, 0);
    for (std::size_t t = 0; t < tri_count; ++t) {
      const double* c = &in.tri_xyz_d[9 * t];
      const Vec3 lo(std::min({c[0], c[3], c[6]}), std::min({c[1], c[4], c[7]}),
                    std::min({c[2], c[5], c[8]}));
      const Vec3 hi(std::max({c[0], c[3], c[6]}), std::max({c[1], c[4], c[7]}),
                    std::max({c[2], c[5], c[8]}));
      const BinRange range = bins_overlapping(in, lo, hi);
      tri_info[4 * t] = in.tri_site[t];
      for (std::size_t a = 0; a < 3; ++a) {
        tri_info[4 * t + 1 + a] = range.lo[a];
        tri_vertices[4 * t + a] = self.tri_vertices[3 * t + a];
      }
    }
    triangles.emplace(StorageBuffer::from_vector(context_, in.tri_xyz));
    triangle_info.emplace(StorageBuffer::from_vector(context_, tri_info));
    bin_offsets.emplace(StorageBuffer::from_vector(context_, in.bin_offsets));
    bin_tris.emplace(StorageBuffer::from_vector(context_, in.bin_tris));
    vertices.emplace(StorageBuffer::from_vector(context_, tri_vertices));
    std::vector<std::uint32_t> samples;
    std::vector<std::int32_t> sample_tris;
    for (Batch& batch : batches) {
      samples.resize(2 * batch.count);
      for (std::size_t k = 0; k < batch.count; ++k) {
        samples[2 * k] = static_cast<std::uint32_t>(in.voxels[batch.first + k]);
        std::memcpy(&samples[2 * k + 1], &in.band[batch.first + k], sizeof(float));
      }
      sample_tris.assign(self.sample_triangle.begin() + static_cast<std::ptrdiff_t>(batch.first),
                         self.sample_triangle.begin() + static_cast<std::ptrdiff_t>(batch.first + batch.count));
      batch.samples.emplace(StorageBuffer::from_vector(context_, samples));
      batch.sample_triangles.emplace(StorageBuffer::from_vector(context_, sample_tris));
      batch.results.emplace(context_, 16 * batch.count, GL_STREAM_READ);
    }
  });

  const double extent = input_extent(in);
  program_.set_float("cell", static_cast<float>(in.grid.cell));
  program_.set_int("dims_x", in.grid.dims[0]);
  program_.set_int("dims_y", in.grid.dims[1]);
  program_.set_int("dims_z", in.grid.dims[2]);
  program_.set_int("bin_size", in.bin_size);
  program_.set_int("bin_dims_x", in.bin_dims[0]);
  program_.set_int("bin_dims_y", in.bin_dims[1]);
  // Rounded up to float: the margin must not shrink (see dvd2_gather.comp).
  program_.set_float("prefilter_margin",
                     std::nextafter(static_cast<float>(2.0 * GlVoronoiBackend::float32_error_bound(extent)),
                                    std::numeric_limits<float>::infinity()));
  triangles->bind(0);
  triangle_info->bind(1);
  bin_offsets->bind(2);
  bin_tris->bind(3);
  vertices->bind(7);

  out.compute_ms = finish_timed_ms(context_, [&] {
    for (const Batch& batch : batches) {
      batch.samples->bind(4);
      batch.results->bind(5);
      batch.sample_triangles->bind(6);
      program_.set_uint("sample_count", static_cast<GLuint>(batch.count));
      dispatch(context_, program_, group_count(batch.count, static_cast<GLuint>(local_size)));
      ++last_dispatch_count_;
    }
    memory_barrier(context_);
  });

  out.readback_ms = finish_timed_ms(context_, [&] {
    for (const Batch& batch : batches) {
      const std::vector<std::int32_t> results = batch.results->download_vector<std::int32_t>(4 * batch.count);
      for (std::size_t k = 0; k < batch.count; ++k) {
        std::memcpy(&out.dist[batch.first + k], &results[4 * k], sizeof(float));
        last_nearest_[batch.first + k] = results[4 * k + 1];
      }
    }
  });
  return out;
}

}  // namespace vproxq::gl
