#pragma once
// Nearest segment of every query point on the GPU, brute force (shaders/point_segment_distance
// .comp). A smoke test of the GL compute path and the template for Stage II's host code:
// upload, dispatch in batches, barrier, readback, with the three times measured.
#include "gl/compute.hpp"

#include <cstdint>
#include <vector>

namespace vproxq::gl {

struct NearestSegmentsOptions {
  GLuint local_size = 64;  ///< work group size (LOCAL_SIZE define of the shader)
  /// Work groups per dispatch; 0: GL_MAX_COMPUTE_WORK_GROUP_COUNT (tests use small values to
  /// exercise batching).
  GLuint max_groups_per_dispatch = 0;
};

struct NearestSegmentsResult {
  /// Per point: index of the nearest segment, ties to the smallest; kNoSegment when M = 0.
  std::vector<std::uint32_t> index;
  /// Per point: float32 distance to that segment (+inf when M = 0).
  std::vector<float> distance;
  GpuTimings timings;
  double compile_ms = 0;  ///< compiling and linking the program (not part of `timings`)
  static constexpr std::uint32_t kNoSegment = 0xFFFFFFFFu;
};

/// `points_xyz`: 3 floats per point; `segments_xyz`: 6 floats per segment (a then b).
/// Throws std::invalid_argument when a size is not a multiple of 3 resp. 6, GlError /
/// ShaderError on GL failures. `context` must be current on the calling thread.
NearestSegmentsResult nearest_segments_gpu(const Context& context,
                                           const std::vector<float>& points_xyz,
                                           const std::vector<float>& segments_xyz,
                                           const NearestSegmentsOptions& options = {});

}  // namespace vproxq::gl
