#include "gl/point_segment_distance.hpp"

#include <algorithm>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>

namespace vproxq::gl {

NearestSegmentsResult nearest_segments_gpu(const Context& context,
                                           const std::vector<float>& points_xyz,
                                           const std::vector<float>& segments_xyz,
                                           const NearestSegmentsOptions& options) {
  if (points_xyz.size() % 3 != 0) {
    throw std::invalid_argument("nearest_segments_gpu: point array size " +
                                std::to_string(points_xyz.size()) + " is not a multiple of 3");
  }
  if (segments_xyz.size() % 6 != 0) {
    throw std::invalid_argument("nearest_segments_gpu: segment array size " +
                                std::to_string(segments_xyz.size()) + " is not a multiple of 6");
  }
  const std::size_t point_count = points_xyz.size() / 3;
  const std::size_t segment_count = segments_xyz.size() / 6;
  constexpr auto kMaxCount = static_cast<std::size_t>(std::numeric_limits<GLuint>::max() / 6);
  if (point_count > kMaxCount || segment_count > kMaxCount) {
    throw std::invalid_argument("nearest_segments_gpu: too many points or segments");
  }

  NearestSegmentsResult result;
  std::optional<ComputeProgram> program;
  result.compile_ms = finish_timed_ms(context, [&] {
    program.emplace(ComputeProgram::from_embedded(
        context, "point_segment_distance",
        {{"LOCAL_SIZE", std::to_string(options.local_size)}}));
  });
  program->set_uint("point_count", static_cast<GLuint>(point_count));
  program->set_uint("segment_count", static_cast<GLuint>(segment_count));

  std::optional<StorageBuffer> points, segments, index, distance;
  result.timings.upload_ms = finish_timed_ms(context, [&] {
    points.emplace(StorageBuffer::from_vector(context, points_xyz));
    segments.emplace(StorageBuffer::from_vector(context, segments_xyz));
    index.emplace(context, point_count * sizeof(std::uint32_t), GL_STREAM_READ);
    distance.emplace(context, point_count * sizeof(float), GL_STREAM_READ);
  });
  points->bind(0);
  segments->bind(1);
  index->bind(2);
  distance->bind(3);

  // Batches of at most GL_MAX_COMPUTE_WORK_GROUP_COUNT[0] groups along x.
  const std::size_t local_size = program->local_size()[0];
  std::size_t groups_per_dispatch =
      static_cast<std::size_t>(context.info().max_work_group_count[0]);
  if (options.max_groups_per_dispatch > 0) {
    groups_per_dispatch =
        std::min<std::size_t>(groups_per_dispatch, options.max_groups_per_dispatch);
  }
  const std::size_t batch = local_size * groups_per_dispatch;
  std::optional<GpuTimer> timer;
  if (!context.info().software && GpuTimer::supported(context)) timer.emplace(context);
  result.timings.compute_ms = finish_timed_ms(context, [&] {
    if (timer) timer->begin();
    for (std::size_t first = 0; first < point_count; first += batch) {
      const std::size_t count = std::min(batch, point_count - first);
      program->set_uint("first_point", static_cast<GLuint>(first));
      dispatch(context, *program, group_count(count, static_cast<GLuint>(local_size)));
    }
    if (timer) timer->end();
    memory_barrier(context);
  });
  if (timer) result.timings.gpu_compute_ms = timer->elapsed_ms();

  result.timings.readback_ms = finish_timed_ms(context, [&] {
    result.index = index->download_vector<std::uint32_t>(point_count);
    result.distance = distance->download_vector<float>(point_count);
  });
  return result;
}

}  // namespace vproxq::gl
