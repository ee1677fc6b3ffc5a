#include "gl/dvd_gather_common.hpp"

#include "core/voronoi/bins.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <stdexcept>

namespace vproxq::gl {

double dvd_input_extent(const DvdInput& in) {
  double extent = in.grid.cell *
                  static_cast<double>(*std::max_element(in.grid.dims.begin(), in.grid.dims.end()));
  for (const double c : in.tri_xyz_d) extent = std::max(extent, std::abs(c));
  return extent;
}

void check_dvd_addressable(const DvdInput& in, const std::string& who) {
  for (const std::int32_t d : in.grid.dims) {
    if (d >= (1 << 23)) {
      throw std::invalid_argument(who + ": a grid side of " + std::to_string(d) +
                                  " voxels is not exact in float32 (limit 2^23)");
    }
  }
  if (in.tri_xyz.size() != in.tri_xyz_d.size()) {
    throw std::invalid_argument(who + ": tri_xyz and tri_xyz_d differ in size");
  }
}

std::vector<std::pair<std::size_t, std::size_t>> plan_batches(const Context& context,
                                                              const ComputeProgram& program,
                                                              std::size_t count,
                                                              unsigned max_groups) {
  const ContextInfo& info = context.info();
  const std::size_t local_size = program.local_size()[0];
  std::size_t groups = static_cast<std::size_t>(info.max_work_group_count[0]);
  if (max_groups > 0) groups = std::min<std::size_t>(groups, max_groups);
  std::size_t batch_size = local_size * groups;
  const auto block_limit = static_cast<std::size_t>(info.max_ssbo_block_size) / 16;
  if (block_limit > 0) batch_size = std::min(batch_size, block_limit / local_size * local_size);
  batch_size = std::max(batch_size, local_size);
  std::vector<std::pair<std::size_t, std::size_t>> batches;
  for (std::size_t first = 0; first < count; first += batch_size)
    batches.emplace_back(first, std::min(batch_size, count - first));
  return batches;
}

DvdSharedBuffers DvdSharedBuffers::upload(const Context& context, const DvdInput& in) {
  const std::size_t tri_count = in.tri_site.size();
  // Per triangle (dvd2_gather.comp): site and first bin, then 0 and last bin.
  std::vector<std::int32_t> tri_info(8 * tri_count);
  for (std::size_t t = 0; t < tri_count; ++t) {
    const double* c = &in.tri_xyz_d[9 * t];
    const Vec3 lo(std::min({c[0], c[3], c[6]}), std::min({c[1], c[4], c[7]}),
                  std::min({c[2], c[5], c[8]}));
    const Vec3 hi(std::max({c[0], c[3], c[6]}), std::max({c[1], c[4], c[7]}),
                  std::max({c[2], c[5], c[8]}));
    const BinRange range = bins_overlapping(in, lo, hi);
    tri_info[8 * t] = in.tri_site[t];
    for (std::size_t a = 0; a < 3; ++a) {
      tri_info[8 * t + 1 + a] = range.lo[a];
      tri_info[8 * t + 5 + a] = range.hi[a];
    }
  }
  return {StorageBuffer::from_vector(context, in.tri_xyz),
          StorageBuffer::from_vector(context, tri_info),
          StorageBuffer::from_vector(context, in.bin_offsets),
          StorageBuffer::from_vector(context, in.bin_tris)};
}

void DvdSharedBuffers::bind() const {
  triangles.bind(0);
  triangle_info.bind(1);
  bin_offsets.bind(2);
  bin_tris.bind(3);
}

DvdInput with_samples(const DvdInput& in, const std::vector<std::size_t>& picks) {
  DvdInput part = in;
  part.voxels.clear();
  part.band.clear();
  part.exclude_site.clear();
  for (const std::size_t k : picks) {
    part.voxels.push_back(in.voxels[k]);
    part.band.push_back(in.band[k]);
    if (!in.exclude_site.empty()) part.exclude_site.push_back(in.exclude_site[k]);
  }
  return part;
}

std::vector<std::uint32_t> pack_samples(const DvdInput& in, std::size_t first, std::size_t count) {
  std::vector<std::uint32_t> samples(4 * count);
  const std::int64_t dx = in.grid.dims[0], dy = in.grid.dims[1];
  for (std::size_t k = 0; k < count; ++k) {
    const std::int64_t id = in.voxels[first + k];
    samples[4 * k] = static_cast<std::uint32_t>(id % dx);
    samples[4 * k + 1] = static_cast<std::uint32_t>((id / dx) % dy);
    samples[4 * k + 2] = static_cast<std::uint32_t>(id / (dx * dy));
    std::memcpy(&samples[4 * k + 3], &in.band[first + k], sizeof(float));
  }
  return samples;
}

void set_dvd_uniforms(ComputeProgram& program, const DvdInput& in, double error_bound) {
  program.set_float("cell", static_cast<float>(in.grid.cell));
  program.set_int("dims_x", in.grid.dims[0]);
  program.set_int("dims_y", in.grid.dims[1]);
  program.set_int("dims_z", in.grid.dims[2]);
  program.set_int("bin_size", in.bin_size);
  program.set_int("bin_dims_x", in.bin_dims[0]);
  program.set_int("bin_dims_y", in.bin_dims[1]);
  program.set_float("prefilter_margin", std::nextafter(static_cast<float>(2.0 * error_bound),
                                                       std::numeric_limits<float>::infinity()));
}

}  // namespace vproxq::gl
