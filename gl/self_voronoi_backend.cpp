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
#include "core/voronoi/cpu_gather.hpp"
#include "core/parallel.hpp"
#include "gl/dvd_gather_common.hpp"
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
  check_dvd_addressable(in, "GlSelfVoronoiBackend");
  SelfDvdOutput out;
  last_dispatch_count_ = 0;
  const std::size_t sample_count = in.voxels.size();
  const std::size_t tri_count = in.tri_site.size();
  out.dist.resize(sample_count);
  last_nearest_.assign(sample_count, kNoIndex);
  if (sample_count == 0) return out;

  // One dispatch per batch, each with its own sample, sample-triangle and result buffers.
  struct Batch {
    std::size_t first, count;
    StorageBuffer samples, sample_triangles, results;
  };
  std::vector<Batch> batches;
  std::optional<DvdSharedBuffers> shared;
  std::optional<StorageBuffer> vertices;
  out.upload_ms = finish_timed_ms(context_, [&] {
    shared.emplace(DvdSharedBuffers::upload(context_, in));
    std::vector<std::int32_t> tri_vertices(4 * tri_count, 0);
    for (std::size_t t = 0; t < tri_count; ++t)
      for (std::size_t a = 0; a < 3; ++a) tri_vertices[4 * t + a] = self.tri_vertices[3 * t + a];
    vertices.emplace(StorageBuffer::from_vector(context_, tri_vertices));
    // Per sample (binding 6): its triangle, and the ids of its object's triangles, which the
    // shader visits in one run per bin: consecutive when triangles are listed in object order,
    // else all triangles.
    const bool sorted = std::is_sorted(in.tri_site.begin(), in.tri_site.end());
    std::vector<std::int32_t> sample_tris;
    for (const auto& [first, count] : plan_batches(context_, program_, sample_count, options_.max_groups_per_dispatch)) {
      sample_tris.assign(4 * count, 0);
      for (std::size_t k = 0; k < count; ++k) {
        const std::int32_t f = self.sample_triangle[first + k];
        const SkippedTriangles run = site_triangles(in, sorted, in.tri_site[static_cast<std::size_t>(f)]);
        sample_tris[4 * k] = f;
        sample_tris[4 * k + 1] = run.lo;  // 0 when not sorted (site_triangles())
        sample_tris[4 * k + 2] = sorted ? run.hi : static_cast<std::int32_t>(tri_count);
      }
      batches.push_back({first, count, StorageBuffer::from_vector(context_, pack_samples(in, first, count)),
                         StorageBuffer::from_vector(context_, sample_tris),
                         StorageBuffer(context_, 16 * count, GL_STREAM_READ)});
    }
  });

  set_dvd_uniforms(program_, in, GlVoronoiBackend::float32_error_bound(dvd_input_extent(in)));
  shared->bind();
  vertices->bind(7);
  out.compute_ms = dispatch_batches(context_, program_, batches, [](const Batch& batch) {
    batch.samples.bind(4);
    batch.results.bind(5);
    batch.sample_triangles.bind(6);
  }, last_dispatch_count_);

  std::vector<std::size_t> redo;
  out.readback_ms = finish_timed_ms(context_, [&] {
    for (const Batch& batch : batches) {
      const std::vector<std::int32_t> results = batch.results.download_vector<std::int32_t>(4 * batch.count);
      for (std::size_t k = 0; k < batch.count; ++k) {
        std::memcpy(&out.dist[batch.first + k], &results[4 * k], sizeof(float));
        last_nearest_[batch.first + k] = results[4 * k + 1];
        if (results[4 * k + 2] != 0) redo.push_back(batch.first + k);
      }
    }
  });
  // Samples the shader could not finish (a driver's loop cap: dvd2_gather.comp) are computed
  // by the CPU twin, whose error bound is below this backend's; their last_nearest() is -1.
  last_redone_ = redo.size();
  if (!redo.empty()) {
    SelfDvdInput part;
    part.dvd = with_samples(in, redo);
    part.tri_vertices = self.tri_vertices;
    for (const std::size_t k : redo) part.sample_triangle.push_back(self.sample_triangle[k]);
    const SelfDvdOutput cpu = make_cpu_self_voronoi_backend(resolve_threads(options_.cpu_threads))->compute(part);
    for (std::size_t j = 0; j < redo.size(); ++j) {
      out.dist[redo[j]] = cpu.dist[j];
      last_nearest_[redo[j]] = kNoIndex;
    }
  }
  return out;
}

}  // namespace vproxq::gl
